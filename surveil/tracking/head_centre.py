"""Where a head's centre is: below the top of its silhouettes (not in the paper).

A head's candidates are skin points: the face seen from the front, the neck and ears from
behind. How far below the head's centre that point lies depends on which side the cameras
see and on the person (a bald head, a hood, dark hair over a dark neck): 4 cm for a face,
12 cm for a neck under black hair (docs/tracking.md, "Head centre"). The silhouettes tell
it directly: straight above the skin point, the top of the person's silhouette is the
crown, and the centre lies ``top_to_centre_m`` below the crown in every view.

Pure functions; :class:`surveil.tracking.manager.MultiTargetTracker` smooths the result
per head over time.
"""

from __future__ import annotations

from collections.abc import Iterable

import numpy as np

from surveil.camera import Camera

# an adult head's crown (with its hair) above the head's centre: about 23 cm from chin to
# crown, plus about 1 cm of hair, m (docs/tracking.md, "Head centre")
CROWN_TO_CENTRE_M = 0.125

# half-width of the image columns searched for the crown, at the head's depth, m: inside a
# head (half-width about 7.5 cm), so that a neighbour's head or a hand beside it is not read
CROWN_HALF_WIDTH_M = 0.05


def crown_heights_m(
    heads_m: np.ndarray, camera: Camera, labels: np.ndarray, span_m: float
) -> np.ndarray:
    """(H,) height (m, world z) of the top of the silhouette straight above each head's skin
    point, as one camera sees it; NaN where this view does not tell.

    From a head's projection, the silhouette it lies in is followed up the image columns
    within ``CROWN_HALF_WIDTH_M`` of it; the first row above that holds none of it is the
    crown's. Its line of sight, where it passes the vertical line through the skin point,
    gives the height.

    NaN: the head is behind the camera or outside the image, lies on background, or the
    silhouette goes on for more than ``span_m`` above it (a taller person behind in the same
    silhouette, a hand raised over the head) or up to the image's top edge.

    Parameters
    ----------
    heads_m : (H, 3) float -- the heads' skin points, world frame, m
    camera : Camera
    labels : (h, w) int -- the camera's silhouette labels (``Silhouettes.labels``; 0
        background), h and w the camera's image size
    span_m : float -- how far above a skin point its crown may be, m

    Examples
    --------
    A camera 4 m away at head height sees a silhouette whose top row is the image of a
    point 0.15 m above the skin point:

    >>> from surveil.camera import look_at
    >>> cam = look_at("c", np.array([-4.0, 0, 1.6]), np.array([0.0, 0, 1.6]),
    ...               width=640, height=480, hfov_deg=60)
    >>> top = int(np.ceil(cam.project(np.array([[0.0, 0, 1.75]]))[0][0, 1]))
    >>> labels = np.zeros((480, 640), np.int32)
    >>> labels[top:, 300:340] = 1
    >>> np.round(crown_heights_m(np.array([[0.0, 0, 1.6], [0, 1, 1.6]]), cam, labels, 0.4), 2)
    array([1.75,  nan])
    """
    heads_m = np.asarray(heads_m, dtype=np.float64).reshape(-1, 3)
    out = np.full(len(heads_m), np.nan)
    if len(heads_m) == 0:
        return out
    px, depth = camera.project(heads_m)
    seen = camera.in_image(px, depth)
    w = labels.shape[1]
    px_per_m = float(camera.K[1, 1]) / np.where(seen, depth, 1.0)
    tops = np.full(len(heads_m), np.nan)
    for i in np.flatnonzero(seen).tolist():
        u, v = round(float(px[i, 0])), round(float(px[i, 1]))
        person = labels[v, u]
        v0 = v - round(span_m * px_per_m[i])
        if person == 0 or v0 < 1:
            continue
        half = max(1, round(CROWN_HALF_WIDTH_M * px_per_m[i]))
        rows = (labels[v0 : v + 1, max(0, u - half) : min(w, u + half + 1)] == person).any(axis=1)
        gaps = np.flatnonzero(~rows)
        if len(gaps):
            tops[i] = v0 + int(gaps[-1]) + 1
    found = np.flatnonzero(np.isfinite(tops))
    if len(found) == 0:
        return out
    # the top edge of the crown's row; its line of sight passes over the head
    centre, rays = camera.backproject(np.column_stack([px[found, 0], tops[found] - 0.5]))
    horiz = rays[:, 0] ** 2 + rays[:, 1] ** 2
    off = heads_m[found, :2] - centre[:2]
    t = np.einsum("ij,ij->i", off, rays[:, :2]) / np.maximum(horiz, 1e-12)
    # looking straight down (no height from this view) or the head behind the crown's ray
    ok = (horiz > 1e-12) & (t > 0)
    out[found[ok]] = centre[2] + t[ok] * rays[ok, 2]
    return out


def head_rises_m(
    heads_m: np.ndarray,
    views: Iterable[tuple[Camera, np.ndarray]],
    top_to_centre_m: float,
    max_rise_m: float,
) -> np.ndarray:
    """(H,) how far each head's centre lies above its skin point, from the silhouettes'
    crowns: the median over the views of (crown height - ``top_to_centre_m`` - skin point
    height) among those between 0 and ``max_rise_m``; NaN where no view tells.

    A view whose crown puts the centre below the skin point or more than ``max_rise_m``
    above it sees something else on top: a hand at the top of the silhouette, or a head
    whose hair is camouflaged against the wall behind it.

    Parameters
    ----------
    heads_m : (H, 3) float -- the heads' skin points, world frame, m
    views : (camera, silhouette labels) per camera
    top_to_centre_m : float -- crown (with hair) to head centre, m
    max_rise_m : float

    Examples
    --------
    >>> from surveil.camera import look_at
    >>> cam = look_at("c", np.array([-4.0, 0, 1.6]), np.array([0.0, 0, 1.6]),
    ...               width=640, height=480, hfov_deg=60)
    >>> top = int(np.ceil(cam.project(np.array([[0.0, 0, 1.8]]))[0][0, 1]))
    >>> labels = np.zeros((480, 640), np.int32)
    >>> labels[top:, 300:340] = 1
    >>> np.round(head_rises_m(np.array([[0.0, 0, 1.6]]), [(cam, labels)], 0.12, 0.2), 2)
    array([0.08])
    """
    heads_m = np.asarray(heads_m, dtype=np.float64).reshape(-1, 3)
    span_m = top_to_centre_m + max_rise_m
    crowns = [crown_heights_m(heads_m, cam, labels, span_m) for cam, labels in views]
    if not crowns:
        return np.full(len(heads_m), np.nan)
    rises = np.array(crowns) - (top_to_centre_m + heads_m[:, 2])  # (views, H)
    rises[~((rises >= 0.0) & (rises <= max_rise_m))] = np.nan
    # the median of each column's finite values (np.sort puts NaN last; np.nanmedian costs
    # a hundred times more on arrays this small)
    k = np.isfinite(rises).sum(axis=0)
    rises.sort(axis=0)
    cols = np.arange(rises.shape[1])
    lo, hi = np.maximum(k - 1, 0) // 2, k // 2
    hi = np.minimum(hi, len(rises) - 1)
    return np.where(k > 0, 0.5 * (rises[lo, cols] + rises[hi, cols]), np.nan)
