"""The per-camera stage of a run (background, skin, blobs) as the benchmarks replay it."""

from __future__ import annotations

import time
from collections.abc import Iterator

from surveil.blobs.background import BackgroundModel, learning_frames_after, shadow_region
from surveil.blobs.extract import extract_blobs
from surveil.datatypes import CameraObservation, FrameSet
from surveil.io.recording import Recording
from surveil.io.skin_model import load_camera_skin_models
from surveil.pipeline import PipelineConfig


def observe_recording(
    rec: Recording,
    cfg: PipelineConfig,
    n_people: int | None = None,
    max_frames: int | None = None,
    changed: bool = False,
) -> Iterator[tuple[FrameSet, dict[str, CameraObservation], dict[str, list[float]]]]:
    """Per frame set: the frames, every camera's observation (by camera name) and the seconds
    each camera spent in ``background``, ``skin`` and ``blobs``.

    Background models start on the run's clock as in ``surveil run``
    (:func:`learning_frames_after`); blobs are chosen for ``n_people`` (default: the number
    of silhouettes, where a run uses its tracked heads); each camera's skin model is the one
    a run uses: saved beside the rig (``surveil train-skin``), else the default.
    ``changed``: the silhouettes carry MOG2's changed mask even when ``cfg`` does not ask
    for it.
    """
    skin_models = load_camera_skin_models(rec.rig_path, rec.camera_names)
    models: dict[str, BackgroundModel] = {}
    for fs in rec.framesets(stop=max_frames):
        observations: dict[str, CameraObservation] = {}
        times: dict[str, list[float]] = {"background": [], "skin": [], "blobs": []}
        for cam in rec.camera_names:
            img = fs.images.get(cam)
            if img is None:
                continue
            if cam not in models:
                models[cam] = BackgroundModel(
                    cfg.background,
                    img.shape[:2],
                    learning_frames_after(cfg.background, fs.index),
                    shadow_region=shadow_region(cfg.background, rec.rig, cam, img.shape[:2]),
                )
            t0 = time.perf_counter()
            requests = cfg.background_requests()
            requests["changed"] |= changed
            sil = models[cam].step(img, **requests)
            t1 = time.perf_counter()
            skin = skin_models[cam].classify(img)
            t2 = time.perf_counter()
            blobs = extract_blobs(skin, sil, cfg.blobs, n_people, img)
            t3 = time.perf_counter()
            times["background"].append(t1 - t0)
            times["skin"].append(t2 - t1)
            times["blobs"].append(t3 - t2)
            observations[cam] = CameraObservation(cam, sil, skin, blobs)
        yield fs, observations, times
