"""``surveil synth``: render a scenario into a recording directory with ground truth.

Output layout (formats.md "Recording" plus our ground truth, docs/formats.md):

``recording.toml``, ``rig.yaml`` (the rig *as calibrated*: with the scenario's calibration
error), one ``<cam>.mp4`` (or image folder) and ``<cam>.csv`` timestamps per camera,
``ground_truth/`` (see :mod:`surveil.io.ground_truth`), and ``preview.png`` on request.

The recording is rendered into a temporary sibling directory and moved into place at the
end, so an interrupted run never leaves a half-written recording behind. Identical inputs
(scenario text, generator version) give identical files, so a recording that is already up
to date is reused instead of re-rendered.
"""

from __future__ import annotations

import dataclasses
import hashlib
import logging
import shutil
import tempfile
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

import cv2
import numpy as np

from surveil.camera import Camera, Rig
from surveil.datatypes import ActivityEvent
from surveil.errors import ConfigError, InputError
from surveil.io.ground_truth import GT_DIR, GroundTruth, MaskClass, write_ground_truth
from surveil.io.video_writer import FrameWriter, write_image
from surveil.synth.actors import Ellipsoid, Part, body_primitives
from surveil.synth.preview import contact_sheet
from surveil.synth.render import CameraRenderer
from surveil.synth.scenario import COMPRESSIONS, Scenario, load_scenario, person_ids
from surveil.synth.timeline import SIDES, Choreography, compile_scenario

log = logging.getLogger(__name__)

# 2: empty-room lead-in
# 3: arm joints and facing in the ground truth
GENERATOR_VERSION = 3
NS = 1_000_000_000
LIMBS = ("head", "left_hand", "right_hand")
ARM_JOINTS = ("shoulder", "elbow", "wrist")  # per side, left then right (joints.csv)
MIN_VISIBLE_FRACTION = 0.5
STRIDE_M = 1.4


@dataclass
class SynthSummary:
    out_dir: Path
    scenario: str
    n_frames: int
    cameras: tuple[str, ...]
    n_camera_frames: int
    dropped: dict[str, int]
    events: tuple[ActivityEvent, ...]
    reused: bool = False
    render_s: float = 0.0
    notes: list[str] = field(default_factory=list)

    def describe(self) -> str:
        lines = [
            f"{'reused up-to-date' if self.reused else 'wrote'} recording {self.out_dir}"
            f" ({self.scenario}): {self.n_frames} frame sets, {len(self.cameras)} cameras"
            f", {self.n_camera_frames} camera frames"
        ]
        if any(self.dropped.values()):
            lines.append(
                "  missing frames (dropped or late start): "
                + ", ".join(f"{c} {n}" for c, n in self.dropped.items())
            )
        for ev in self.events:
            hue = "" if ev.object_hue_deg is None else f" (object hue {ev.object_hue_deg:.0f})"
            lines.append(
                f"  {ev.climax_ns / NS:6.2f} s  {ev.activity:<10} {', '.join(ev.actors)}{hue}"
            )
        return "\n".join(lines)


def perturb_rig(rig: Rig, scenario: Scenario, rng: np.random.Generator) -> Rig:
    """The rig as a (slightly wrong) calibration would report it."""
    eff = scenario.effects
    cams = []
    for cam in rig:
        dr = rng.normal(0, np.radians(eff.calib_rotation_deg), 3)
        R = cv2.Rodrigues(dr)[0] @ cam.R
        centre = cam.centre_m + rng.normal(0, eff.calib_translation_m, 3)
        K = cam.K.copy()
        f = 1 + rng.normal(0, eff.calib_focal_rel)
        K[0, 0] *= f
        K[1, 1] *= f
        cams.append(Camera(cam.name, cam.width, cam.height, K, cam.dist, R, -R @ centre))
    return Rig(tuple(cams))


def scenario_rig(scenario: Scenario, scenario_path: Path) -> Rig:
    """The true rig: a calibration file named by the scenario, or generated corner cameras."""
    from surveil.io.calibration import load_rig
    from surveil.rigs import make_corner_rig

    if scenario.rig.file:
        path = Path(scenario.rig.file)
        if not path.is_absolute():
            path = scenario_path.parent / path
        return load_rig(path)
    return make_corner_rig(
        scenario.rig.n_cameras,
        room_m=scenario.room.size_m[:2],
        height_m=scenario.rig.height_m,
        size=(scenario.rig.width, scenario.rig.height),
        hfov_deg=scenario.rig.hfov_deg,
    )


def object_primitive(
    chor: Choreography,
    name: str,
    t: float,
    poses: dict,
) -> tuple[Ellipsoid, str, np.ndarray]:
    """The object's primitive, its holder label ('' if resting) and centre."""
    obj = chor.objects[name]
    holder, rest = obj.state(t)
    half = obj.size_m / 2
    if holder:
        pid, hand = holder.split("/")
        i = SIDES.index(hand.removesuffix("_hand"))
        pose = poses[pid]
        ax = pose.hand_axes[i]
        outward = ax[:, 2] * (1.0 if i == 0 else -1.0)
        shape = chor.actors[pid].shape
        centre = (
            pose.hands_m[i]
            + outward * (0.5 * shape.hand_thickness_m + half[1] + 0.004)
            + ax[:, 0] * 0.02
        )
        axes = np.column_stack([ax[:, 1], ax[:, 2], ax[:, 0]])
    else:
        centre, axes = rest, np.eye(3)
    kind = 1 if obj.shape == "box" else 0
    return (
        Ellipsoid(
            centre, axes, half, obj.albedo, int(MaskClass.OBJECT), 0, int(Part.OBJECT), kind
        ),
        holder,
        centre,
    )


def synthesise(
    scenario_path: Path,
    out_dir: Path,
    *,
    preview: bool = False,
    preview_times_s: tuple[float, ...] = (),
    overwrite: bool = False,
    on_progress: Callable[[int, int], None] | None = None,
    scene_seed: int | None = None,
    compression: str | None = None,
) -> SynthSummary:
    """Render ``scenario_path`` into the recording directory ``out_dir``.

    ``scene_seed`` replaces the scenario's ``[scene] seed``: another take of the same
    script, with its own timing and motion variations, calibration error, noise and dropped
    frames (held-out recordings for a benchmark tuned on the bundled takes).
    ``compression`` replaces ``[effects] compression``: the same take, pixel for pixel
    before encoding, stored another way (the codec as a held-out condition).

    Raises ConfigError for a bad scenario or a negative ``scene_seed``, InputError if
    ``out_dir`` holds something else and ``overwrite`` is false.
    """
    scenario_path = Path(scenario_path)
    out_dir = Path(out_dir)
    scenario = load_scenario(scenario_path)
    take = b""
    if scene_seed is not None:
        if scene_seed < 0:
            raise ConfigError(f"{scenario_path}: scene seed must be >= 0, got {scene_seed}")
        scenario = dataclasses.replace(
            scenario, scene=dataclasses.replace(scenario.scene, seed=scene_seed)
        )
        take = f" scene seed {scene_seed}".encode()
    if compression is not None and compression != scenario.effects.compression:
        if compression not in COMPRESSIONS:
            raise ConfigError(
                f"compression must be one of {', '.join(COMPRESSIONS)}, got {compression!r}"
            )
        scenario = dataclasses.replace(
            scenario, effects=dataclasses.replace(scenario.effects, compression=compression)
        )
        take += f" compression {compression}".encode()
    digest = hashlib.sha256(
        scenario_path.read_bytes() + take + f"v{GENERATOR_VERSION}".encode()
    ).hexdigest()
    stamp = out_dir / GT_DIR / "scenario.sha256"
    if out_dir.exists():
        if (
            stamp.is_file()
            and stamp.read_text().strip() == digest
            and not overwrite
            and (not preview or (out_dir / "preview.png").is_file())
            and not preview_times_s
        ):
            return _existing_summary(out_dir, scenario)
        if not overwrite and any(out_dir.iterdir()):
            if not stamp.is_file():
                raise InputError(
                    f"{out_dir} exists and is not a recording made by `surveil "
                    f"synth`; choose another --out or delete it"
                )
            raise InputError(
                f"{out_dir} holds an older rendering of a different scenario "
                f"version; pass --force to replace it"
            )
    out_dir.parent.mkdir(parents=True, exist_ok=True)
    tmp = Path(tempfile.mkdtemp(prefix=f".{out_dir.name}-", dir=out_dir.parent))
    try:
        summary = _render(scenario, scenario_path, tmp, preview, preview_times_s, on_progress)
        (tmp / GT_DIR / "scenario.sha256").write_text(digest + "\n")
        # another process may have finished the same rendering meanwhile and be reading it:
        # keep that one (it is identical) rather than delete files under its reader
        same = stamp.is_file() and stamp.read_text().strip() == digest
        if out_dir.exists() and not (same and not overwrite and not preview):
            shutil.rmtree(out_dir)
        if not out_dir.exists():
            tmp.rename(out_dir)
    finally:
        if tmp.exists():
            shutil.rmtree(tmp, ignore_errors=True)
    summary.out_dir = out_dir
    return summary


def _existing_summary(out_dir: Path, scenario: Scenario) -> SynthSummary:
    from surveil.io.ground_truth import load_ground_truth

    gt = load_ground_truth(out_dir)
    return SynthSummary(
        out_dir,
        scenario.scene.name,
        len(gt.frames),
        gt.cameras,
        int(gt.meta.get("n_camera_frames", 0)),
        dict(gt.meta.get("missing_frames", {})),
        gt.events,
        reused=True,
    )


def _render(
    scenario: Scenario,
    scenario_path: Path,
    out: Path,
    preview: bool,
    preview_times_s: tuple[float, ...],
    on_progress: Callable[[int, int], None] | None,
) -> SynthSummary:
    from surveil.io.calibration import save_rig

    t_start = time.perf_counter()
    seed_seq = np.random.SeedSequence(scenario.scene.seed)
    rng_chor, rng_rig, rng_render, rng_time, rng_noise = (
        np.random.default_rng(s) for s in seed_seq.spawn(5)
    )
    true_rig = scenario_rig(scenario, scenario_path)
    written_rig = perturb_rig(true_rig, scenario, rng_rig)
    chor = compile_scenario(scenario, rng_chor)
    fps = scenario.scene.fps
    lead_s = scenario.scene.empty_room_s
    n_frames = int(round((lead_s + scenario.scene.duration_s) * fps))
    period_ns = NS / fps
    eff = scenario.effects
    for cam_name in eff.late_start_s:
        if cam_name not in true_rig:
            raise ConfigError(
                f"{scenario_path}: effects.late_start_s names unknown camera "
                f"{cam_name!r} (rig: {', '.join(true_rig.names)})"
            )
    renderers = {
        cam.name: CameraRenderer(cam, scenario.room, list(scenario.furniture), eff, rng_render)
        for cam in true_rig
    }
    # which camera frames exist, and their recorded timestamps
    cams = true_rig.names
    exists = rng_time.random((n_frames, len(cams))) >= eff.drop_rate
    times = np.arange(n_frames) / fps
    for c, name in enumerate(cams):
        exists[times < eff.late_start_s.get(name, 0.0), c] = False
    jitter = np.clip(
        rng_time.normal(0, eff.jitter_ms * 1e6, exists.shape), -0.3 * period_ns, 0.3 * period_ns
    )
    stamps = np.round(np.arange(n_frames)[:, None] * period_ns + jitter).astype(np.int64)
    stamps = np.maximum(stamps, 0)

    writers = {
        name: FrameWriter(
            out, name, eff.compression, fps, renderers[name].cam.size, eff.jpeg_quality
        )
        for name in cams
    }
    ids = person_ids(scenario)
    labels = [f"{pid}/{limb}" for pid in ids for limb in LIMBS]
    positions = np.full((n_frames, len(labels), 3), np.nan)
    visible = np.zeros((n_frames, len(labels), len(cams)), dtype=bool)
    joint_labels = [
        f"{pid}/{side}_{joint}" for pid in ids for side in SIDES for joint in ARM_JOINTS
    ]
    joints = np.full((n_frames, len(joint_labels), 3), np.nan)
    facing = np.full((n_frames, len(ids)), np.nan)
    obj_names = tuple(chor.objects)
    obj_pos = np.full((n_frames, len(obj_names), 3), np.nan)
    held = np.full((n_frames, len(obj_names)), "", dtype=object)
    mask_dir = out / GT_DIR / "masks"
    preview = preview or bool(preview_times_s)
    if preview_times_s:
        preview_frames = sorted(
            {min(n_frames - 1, max(0, round(t * fps))) for t in preview_times_s}
        )
    else:
        preview_frames = _preview_frames(chor, n_frames, fps, lead_s) if preview else []
    preview_images: dict[int, dict[str, np.ndarray]] = {}
    prev_root = {pid: chor.actors[pid].root(0.0) for pid in ids}
    gait = dict.fromkeys(ids, 0.0)
    min_px = max(6, int(12 * (true_rig.cameras[0].width / 640) ** 2))
    for k in range(n_frames):
        # t: choreography time, negative during the empty-room lead-in
        t = k / fps - lead_s
        poses, prims = {}, []
        limb_prims: dict[str, list[int]] = {}
        casters = []
        for pid in ids if t >= 0 else ():
            actor = chor.actors[pid]
            root = actor.root(t)
            step = float(np.linalg.norm(root - prev_root[pid]))
            prev_root[pid] = root
            gait[pid] += 2 * np.pi * step / STRIDE_M
            amp = float(np.clip(step * fps / 0.8, 0, 1))
            pose = actor.pose(t, gait[pid], amp)
            poses[pid] = pose
            base = len(prims)
            body = body_primitives(actor.shape, actor.look, pose, actor.number)
            prims.extend(body)
            parts = [int(p.part) for p in body]
            limb_prims[f"{pid}/head"] = [
                base + parts.index(Part.HEAD),
                base + parts.index(Part.HAIR),
            ]
            limb_prims[f"{pid}/left_hand"] = [base + parts.index(Part.LEFT_HAND)]
            limb_prims[f"{pid}/right_hand"] = [base + parts.index(Part.RIGHT_HAND)]
            j = labels.index(f"{pid}/head")
            positions[k, j] = pose.head_m
            positions[k, j + 1] = pose.hands_m[0]
            positions[k, j + 2] = pose.hands_m[1]
            j = joint_labels.index(f"{pid}/left_shoulder")
            for i in range(len(SIDES)):
                joints[k, j + 3 * i : j + 3 * i + 3] = (
                    pose.shoulders_m[i],
                    pose.elbows_m[i],
                    pose.wrists_m[i],
                )
            facing[k, ids.index(pid)] = (pose.yaw_rad + np.pi) % (2 * np.pi) - np.pi
            light_xy = np.array([-0.45, -0.26])  # shadows fall away from the light
            for h, w in ((0.0, 0.7), (0.6, 0.5), (1.2, 0.35)):
                casters.append((root[0] + h * light_xy[0], root[1] + h * light_xy[1], w))
        for o, name in enumerate(obj_names):
            if t < 0 and chor.objects[name].state(0.0)[0]:
                continue  # held from the start: arrives with its holder
            prim, holder, centre = object_primitive(chor, name, max(t, 0.0), poses)
            prims.append(prim)
            obj_pos[k, o] = centre
            held[k, o] = holder
        illumination = 1.0 + eff.illumination_drift * (
            np.sin(2 * np.pi * t / 23.0 + 1.0) + 0.5 * np.sin(2 * np.pi * t / 7.3)
        )
        write_mask = eff.mask_every > 0 and k % eff.mask_every == 0
        for c, name in enumerate(cams):
            if not exists[k, c]:
                continue
            r = renderers[name]
            image, winner, full_area, boxes = r.render(
                prims, np.array(casters), illumination, rng_noise
            )
            writers[name].write(image, int(stamps[k, c]))
            # visible: the limb's centre is in the image and not occluded, and at least
            # MIN_VISIBLE_FRACTION of the area it would cover unoccluded shows
            px, depth = r.cam.project(positions[k])
            inside = r.cam.in_image(px, depth)
            centre_px, centre_ok = r.canvas_pixel(positions[k])
            centre_winner = np.where(centre_ok, winner[centre_px[:, 1], centre_px[:, 0]], -1)
            for j, label in enumerate(labels if t >= 0 else ()):
                idx = limb_prims[label]
                full = max(int(full_area[i]) for i in idx)
                if full < min_px or not inside[j] or centre_winner[j] not in idx:
                    continue
                shown = 0
                for i in idx:
                    i0, i1, j0, j1 = boxes[i]
                    shown += int(np.count_nonzero(winner[i0:i1, j0:j1] == i))
                visible[k, j, c] = shown >= min_px and shown >= MIN_VISIBLE_FRACTION * full
            if write_mask or k in preview_frames:
                masks = _label_image(prims, winner, r)
                if write_mask:
                    write_image(mask_dir / name / f"{k:06d}.png", masks)
            if k in preview_frames:
                preview_images.setdefault(k, {})[name] = image
        if on_progress is not None:
            on_progress(k + 1, n_frames)
    for w in writers.values():
        w.close()
    missing = {name: int(n_frames - exists[:, c].sum()) for c, name in enumerate(cams)}
    n_camera_frames = int(exists.sum())
    render_s = time.perf_counter() - t_start
    save_rig(written_rig, out / "rig.yaml")
    save_rig(true_rig, out / GT_DIR / "rig_true.yaml")
    _write_recording_toml(out, scenario, cams, writers)
    meta = {
        "scenario": scenario.scene.name,
        "fps": fps,
        "seed": scenario.scene.seed,
        "generator_version": GENERATOR_VERSION,
        "n_camera_frames": n_camera_frames,
        "missing_frames": missing,
        "mask_every": eff.mask_every,
        "empty_room_s": lead_s,
        "min_visible_fraction": MIN_VISIBLE_FRACTION,
        "persons": [
            {
                "id": pid,
                "height_m": p.height_m,
                "skin": p.skin,
                "shirt": p.shirt,
                "sleeves": p.sleeves,
            }
            for pid, p in zip(ids, scenario.people, strict=False)
        ],
        "objects": [
            {"name": n, "hue_deg": chor.objects[n].hue_deg, "shape": chor.objects[n].shape}
            for n in obj_names
        ],
        "render_ms_per_camera_frame": round(1000 * render_s / max(n_camera_frames, 1), 2),
    }
    lead_ns = round(lead_s * NS)
    events = tuple(
        dataclasses.replace(
            ev,
            start_ns=ev.start_ns + lead_ns,
            climax_ns=ev.climax_ns + lead_ns,
            end_ns=ev.end_ns + lead_ns,
        )
        for ev in chor.events
    )
    gt = GroundTruth(
        frames=np.arange(n_frames),
        t_ns=np.round(times * NS).astype(np.int64),
        labels=tuple(labels),
        cameras=cams,
        positions_m=positions,
        visible=visible,
        object_names=obj_names,
        object_hue_deg=np.array([chor.objects[n].hue_deg for n in obj_names]),
        object_positions_m=obj_pos,
        held_by=held,
        events=events,
        meta=meta,
        joint_labels=tuple(joint_labels),
        joint_positions_m=joints,
        persons=tuple(ids),
        facing_yaw_rad=facing,
    )
    write_ground_truth(out / GT_DIR, gt)
    if preview:
        write_image(
            out / "preview.png", contact_sheet(preview_images, gt, true_rig, scenario.scene.name)
        )
    log.info(
        "rendered %s: %d frames x %d cameras in %.1f s",
        scenario.scene.name,
        n_frames,
        len(cams),
        render_s,
    )
    return SynthSummary(
        out,
        scenario.scene.name,
        n_frames,
        cams,
        n_camera_frames,
        missing,
        events,
        render_s=render_s,
    )


def _label_image(prims: list[Ellipsoid], winner: np.ndarray, r: CameraRenderer) -> np.ndarray:
    """BGR uint8 mask in the real image: B = class, G = person, R = part."""
    lut = np.zeros((len(prims) + 1, 3), dtype=np.uint8)
    for i, p in enumerate(prims):
        lut[i + 1] = (p.mask_class, p.person, p.part)
    canvas = lut[winner.astype(np.int32) + 1]
    static = winner < 0
    canvas[static, 0] = r.static_class[static]
    return r.distort_labels(canvas)


def _preview_frames(chor: Choreography, n_frames: int, fps: float, lead_s: float) -> list[int]:
    """Up to four frames: event climaxes first, else evenly spaced after the lead-in."""
    picks = [min(n_frames - 1, int(round((e.climax_ns / NS + lead_s) * fps))) for e in chor.events]
    picks = sorted(set(picks))
    if len(picks) > 4:
        picks = [picks[i] for i in np.linspace(0, len(picks) - 1, 4).round().astype(int)]
    while len(picks) < 4:
        extra = [int(x) for x in np.linspace(lead_s * fps, n_frames - 1, 6)[1:-1]]
        for e in extra:
            if len(picks) < 4 and all(abs(e - p) > 2 for p in picks):
                picks.append(e)
        break
    return sorted(picks)


def _write_recording_toml(
    out: Path, scenario: Scenario, cams: tuple[str, ...], writers: dict
) -> None:
    lines = [
        "# written by `surveil synth`; see docs/formats.md",
        'rig = "rig.yaml"',
        f"fps = {scenario.scene.fps!r}",
        "start_time_ns = 0",
        "",
    ]
    for name in cams:
        lines += [
            "[[cameras]]",
            f'name = "{name}"',
            f'video = "{writers[name].video_name}"',
            f'timestamps = "{name}.csv"',
            "",
        ]
    (out / "recording.toml").write_text("\n".join(lines))
