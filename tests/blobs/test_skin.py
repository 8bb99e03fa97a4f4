import numpy as np
import pytest

from surveil.blobs import SkinConfig, compile_skin_lut, default_skin_model, train_skin_classifier
from surveil.blobs.skin import bin_centres, colour_features
from surveil.io.recording import open_recording
from surveil.io.skin_model import load_skin_model, save_skin_model, training_pixels_from_recording


def _toy_data(rng, n=4000):
    px = rng.integers(0, 256, (n, 3)).astype(np.uint8)
    f = colour_features(px, "rgi")
    labels = (f[:, 0] > 0.4) & (f[:, 1] < 0.35) & (f[:, 2] > 0.2)  # a reddish region
    return px, labels


@pytest.fixture
def toy(rng):
    px, labels = _toy_data(rng)
    clf = train_skin_classifier(px, labels, SkinConfig(max_iter=50), rng)
    return clf, compile_skin_lut(clf, "rgi", bits=6)


def test_lut_agrees_with_its_classifier(toy, rng):
    clf, model = toy
    centres = bin_centres(6)
    exact = clf.predict_proba(colour_features(centres, "rgi"))[:, 1] >= 0.5
    assert (exact == model.lut.reshape(-1)).mean() >= 0.99
    px = rng.integers(0, 256, (20000, 3)).astype(np.uint8)
    direct = clf.predict_proba(colour_features(px, "rgi"))[:, 1] >= 0.5
    assert (model.classify(px[:, None, :])[:, 0] == direct).mean() >= 0.98


def test_classify_shape_and_dtype(toy):
    out = toy[1].classify(np.zeros((7, 5, 3), np.uint8))
    assert out.shape == (7, 5) and out.dtype == bool
    with pytest.raises(TypeError, match="bgr"):
        toy[1].classify(np.zeros((7, 5, 3), np.float32))


def test_save_load_round_trip(toy, tmp_path):
    path = tmp_path / "m.npz"
    save_skin_model(toy[1], path)
    back = load_skin_model(path)
    assert back.bits == 6 and np.array_equal(back.lut, toy[1].lut)
    assert back.meta == toy[1].meta


def test_training_needs_both_classes(rng):
    px = np.zeros((10, 3), np.uint8)
    with pytest.raises(ValueError, match="labels"):
        train_skin_classifier(px, np.zeros(10, bool), SkinConfig(), rng)


def _scores(recording):
    px, truth = training_pixels_from_recording(recording, pixel_step=1)
    pred = default_skin_model().classify(px[:, None, :])[:, 0]
    tp = np.count_nonzero(pred & truth)
    return tp / max(np.count_nonzero(pred), 1), tp / np.count_nonzero(truth)


def test_default_model_finds_synthetic_skin(small_recording):
    open_recording(small_recording)
    precision, recall = _scores(small_recording)
    # measured (whole frame, every pixel): see docs/blobs.md; a regression guard only
    assert recall >= 0.15


@pytest.mark.xfail(reason="target P, R >= 0.8 not reached: see docs/blobs.md", strict=True)
def test_default_model_precision_recall_target(small_recording):
    precision, recall = _scores(small_recording)
    assert precision >= 0.8 and recall >= 0.8


def test_default_model_on_astronaut_photo():
    from skimage import data

    bgr = np.ascontiguousarray(data.astronaut()[..., ::-1])
    skin = default_skin_model().classify(bgr)
    assert skin[100:160, 225:255].mean() >= 0.6  # right half of the face (not trained on)
    assert skin[0:60, 300:380].mean() <= 0.1  # grey backdrop (not trained on)
