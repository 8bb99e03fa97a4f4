"""The per-camera stage of a run (``surveil.pipeline.observe_cameras``: background, skin,
crowns, blobs) as the benchmarks replay it."""

from __future__ import annotations

from collections.abc import Iterator

from surveil.blobs.background import BackgroundModel
from surveil.blobs.extract import SceneryMask
from surveil.datatypes import CameraObservation, FrameSet
from surveil.io.recording import Recording
from surveil.io.skin_model import load_camera_skin_models
from surveil.pipeline import CAMERA_STEPS, PipelineConfig, new_background, observe_cameras


def observe_recording(
    rec: Recording,
    cfg: PipelineConfig,
    n_people: int | None = None,
    max_frames: int | None = None,
    changed: bool = False,
    skin_near_people: bool = False,
) -> Iterator[tuple[FrameSet, dict[str, CameraObservation], dict[str, list[float]]]]:
    """Per frame set: the frames, every camera's observation (by camera name) and the seconds
    each camera spent in ``background``, ``skin``, ``blobs`` and ``crowns``.

    Background models start on the run's clock as in ``surveil run``
    (:func:`learning_frames_after`); blobs are chosen for ``n_people`` (default: the view's
    silhouettes, with ``[blobs] people_from_crowns`` also the frame set's crowns, where a run
    also counts its tracked heads); each camera's skin model is the one
    a run uses: saved beside the rig (``surveil train-skin``), else the default. As in a run,
    the silhouettes' distances are exact only up to the run's cap (beyond it nothing changes
    the candidates). ``skin_near_people``: skin is classified only in the boxes around the
    silhouettes, as a run does (the same blobs, a run's stage time); else everywhere, for the
    diagnostics that look at skin far from people.
    ``changed``: the silhouettes carry MOG2's changed mask even when ``cfg`` does not ask
    for it.
    """
    skin_models = load_camera_skin_models(rec.rig_path, rec.camera_names)
    models: dict[str, BackgroundModel] = {}
    scenery = {cam: SceneryMask(model) for cam, model in skin_models.items()}
    for fs in rec.framesets(stop=max_frames):
        images = {cam: fs.images[cam] for cam in rec.camera_names if cam in fs.images}
        for cam, img in images.items():
            if cam not in models:
                models[cam] = new_background(cfg, rec.rig, cam, img.shape[:2], fs.index)
        observations, seconds = observe_cameras(
            cfg,
            rec.rig,
            images,
            models,
            skin_models,
            scenery,
            n_people,
            changed=changed,
            skin_everywhere=not skin_near_people,
        )
        times: dict[str, list[float]] = {step: [] for step in CAMERA_STEPS}
        for cam_seconds in seconds.values():
            for step, sec in cam_seconds.items():
                times[step].append(sec)
        yield fs, observations, times
