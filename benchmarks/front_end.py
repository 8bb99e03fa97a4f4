"""The per-camera stage of a run (background, skin, blobs) as the benchmarks replay it."""

from __future__ import annotations

import time
from collections.abc import Iterator

from surveil.blobs.background import BackgroundModel, learning_frames_after, shadow_region
from surveil.blobs.extract import SceneryMask, blob_margin_px, extract_blobs
from surveil.datatypes import CameraObservation, FrameSet
from surveil.io.recording import Recording
from surveil.io.skin_model import load_camera_skin_models
from surveil.pipeline import PipelineConfig, silhouette_distance_cap_px
from surveil.recon.crowns import silhouette_crowns


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
    (:func:`learning_frames_after`); blobs are chosen for ``n_people`` (default: the number
    of silhouettes, where a run uses its tracked heads); each camera's skin model is the one
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
        observations: dict[str, CameraObservation] = {}
        times: dict[str, list[float]] = {"background": [], "skin": [], "blobs": [], "crowns": []}
        for cam in rec.camera_names:
            img = fs.images.get(cam)
            if img is None:
                continue
            if cam not in models:
                models[cam] = BackgroundModel(
                    cfg.background,
                    img.shape[:2],
                    learning_frames_after(cfg.background, fs.index),
                    silhouette_distance_cap_px(cfg),
                    shadow_region(cfg.background, rec.rig, cam, img.shape[:2]),
                )
            t0 = time.perf_counter()
            requests = cfg.background_requests()
            requests["changed"] |= changed
            sil = models[cam].step(img, **requests)
            t1 = time.perf_counter()
            boxes = (
                sil.boxes(blob_margin_px(cfg.blobs, img.shape[1])) if skin_near_people else None
            )
            skin = skin_models[cam].classify(img, boxes)
            t2 = time.perf_counter()
            on_scenery = scenery[cam].mask(models[cam]) if cfg.blobs.scenery_share > 0 else None
            blobs = extract_blobs(skin, sil, cfg.blobs, n_people, img, on_scenery)
            t3 = time.perf_counter()
            crowns_cfg = cfg.candidates.crowns
            crowns = (
                silhouette_crowns(sil, rec.rig[cam], crowns_cfg) if crowns_cfg.enabled else None
            )
            t4 = time.perf_counter()
            times["background"].append(t1 - t0)
            times["skin"].append(t2 - t1)
            times["blobs"].append(t3 - t2)
            times["crowns"].append(t4 - t3)
            observations[cam] = CameraObservation(cam, sil, skin, blobs, crowns)
        yield fs, observations, times
