"""A small ray-casting renderer for synthetic camera frames.

Per camera, the static room (textured floor and walls, furniture, a skin-toned table and
wall panel, a colourful poster) is ray-cast once into an *ideal* undistorted canvas with its
depth. Every frame, the people and objects (ellipsoids and boxes) are ray-cast only inside
their projected bounding boxes and composited with a z-buffer (correct occlusion, also by the
furniture), shaded by a directional light plus ambient and fill, over soft floor shadows.
The canvas is then warped through the camera's real lens distortion (one ``cv2.remap`` with
a precomputed map), and the sensor is simulated: slow illumination drift, per-camera gain and
white balance, vignetting, read and photon noise, 8-bit quantisation. Video compression
happens when the frames are written.

The winner buffer (which primitive each canvas pixel shows) gives the ground truth for free:
per-pixel class/person/part masks and per-limb visibility (fraction of the limb's own
projected area that is not occluded).
"""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np

from surveil.camera import Camera
from surveil.io.ground_truth import MaskClass
from surveil.synth.actors import Ellipsoid
from surveil.synth.scenario import EffectsSpec, FurnitureSpec, RoomSpec, parse_rgb

NEAR_M = 0.05
AMBIENT, DIFFUSE, FILL = 0.38, 0.62, 0.18


@dataclass(frozen=True, slots=True)
class StaticBox:
    """An axis-aligned (after yaw) box of the static scene."""

    centre_m: np.ndarray
    half_m: np.ndarray
    yaw_rad: float
    albedo: np.ndarray  # BGR [0, 1]
    mask_class: int


def furniture_boxes(spec: FurnitureSpec) -> list[StaticBox]:
    """Boxes of one piece of furniture: a table is a top and four legs, a cabinet one box."""
    albedo = parse_rgb(spec.colour, f"furniture {spec.name}.colour")
    skinlike = spec.colour == "wood"
    cls = int(MaskClass.SKIN_DISTRACTOR if skinlike else MaskClass.BACKGROUND)
    cx, cy = spec.centre_m
    sx, sy, h = spec.size_m
    yaw = float(np.radians(spec.yaw_deg))
    if spec.kind == "cabinet":
        return [
            StaticBox(
                np.array([cx, cy, h / 2]), np.array([sx / 2, sy / 2, h / 2]), yaw, albedo, cls
            )
        ]
    top = 0.035
    boxes = [
        StaticBox(
            np.array([cx, cy, h - top / 2]), np.array([sx / 2, sy / 2, top / 2]), yaw, albedo, cls
        )
    ]
    c, s = np.cos(yaw), np.sin(yaw)
    for dx in (-1, 1):
        for dy in (-1, 1):
            lx, ly = dx * (sx / 2 - 0.05), dy * (sy / 2 - 0.05)
            boxes.append(
                StaticBox(
                    np.array([cx + c * lx - s * ly, cy + s * lx + c * ly, (h - top) / 2]),
                    np.array([0.025, 0.025, (h - top) / 2]),
                    yaw,
                    albedo * 0.8,
                    cls,
                )
            )
    return boxes


def _hash01(*ints: np.ndarray) -> np.ndarray:
    """Deterministic pseudo-random values in [0, 1) from integer lattice coordinates."""
    h = np.zeros(np.broadcast(*ints).shape, dtype=np.uint64)
    for k, v in enumerate(ints):
        h ^= (v.astype(np.int64).astype(np.uint64) + np.uint64(0x9E3779B9 + k)) * np.uint64(
            0x85EBCA6B
        )
        h ^= h >> np.uint64(13)
        h *= np.uint64(0xC2B2AE35)
        h ^= h >> np.uint64(16)
    return (h % np.uint64(10007)).astype(np.float32) / np.float32(10007)


def _value_noise(x: np.ndarray, y: np.ndarray, cell: float, seed: int) -> np.ndarray:
    """Smooth value noise in [0, 1) at world coordinates (bilinear lattice interpolation)."""
    gx, gy = x / cell, y / cell
    ix, iy = np.floor(gx), np.floor(gy)
    fx, fy = gx - ix, gy - iy
    sx, sy = fx * fx * (3 - 2 * fx), fy * fy * (3 - 2 * fy)
    ix, iy = ix.astype(np.int64) + seed * 1000, iy.astype(np.int64)
    v00, v10 = _hash01(ix, iy), _hash01(ix + 1, iy)
    v01, v11 = _hash01(ix, iy + 1), _hash01(ix + 1, iy + 1)
    return (v00 * (1 - sx) + v10 * sx) * (1 - sy) + (v01 * (1 - sx) + v11 * sx) * sy


def light_direction(room: RoomSpec) -> np.ndarray:
    """(3,) unit vector towards the main light, world frame."""
    az, el = np.radians(room.light_azimuth_deg), np.radians(room.light_elevation_deg)
    return np.array([np.cos(el) * np.cos(az), np.cos(el) * np.sin(az), np.sin(el)])


def lamp_falloff(points_m: np.ndarray, room: RoomSpec) -> np.ndarray:
    """Brightness falloff away from a ceiling lamp at the room centre."""
    lamp = np.array([room.size_m[0] / 2, room.size_m[1] / 2, room.size_m[2]])
    d2 = np.sum((points_m - lamp) ** 2, axis=-1)
    return (1.15 / (1.0 + d2 / 30.0)).astype(np.float32)


class CameraRenderer:
    """Renders frames of one camera. Stateful only in its precomputed buffers."""

    def __init__(
        self,
        cam: Camera,
        room: RoomSpec,
        furniture: list[FurnitureSpec],
        effects: EffectsSpec,
        rng: np.random.Generator,
    ) -> None:
        self.cam = cam
        self.room = room
        self.effects = effects
        W, H = cam.width, cam.height
        # ideal canvas: where each real (distorted) pixel looks, as undistorted coordinates
        uu, vv = np.meshgrid(np.arange(W, dtype=np.float64), np.arange(H, dtype=np.float64))
        norm = cam.undistort_pixels(np.column_stack([uu.ravel(), vv.ravel()]))
        fx, fy = cam.K[0, 0], cam.K[1, 1]
        px = norm[:, 0] * fx
        py = norm[:, 1] * fy
        margin = 2.0
        self.cx = float(-px.min() + margin)
        self.cy = float(-py.min() + margin)
        self.fx, self.fy = float(fx), float(fy)
        self.canvas_w = int(np.ceil(px.max() + self.cx + margin))
        self.canvas_h = int(np.ceil(py.max() + self.cy + margin))
        self.map_x = (px + self.cx).reshape(H, W).astype(np.float32)
        self.map_y = (py + self.cy).reshape(H, W).astype(np.float32)
        jj, ii = np.meshgrid(
            np.arange(self.canvas_w, dtype=np.float32), np.arange(self.canvas_h, dtype=np.float32)
        )
        self.xn = (jj - np.float32(self.cx)) / np.float32(fx)
        self.yn = (ii - np.float32(self.cy)) / np.float32(fy)
        self.light_cam = (cam.R @ light_direction(room)).astype(np.float32)
        self._render_static(furniture)
        # sensor: gain, white balance and vignetting in one per-pixel factor map
        gain = 1.0 + effects.gain_spread * rng.standard_normal()
        wb = 1.0 + effects.white_balance_spread * rng.standard_normal(3)
        r2 = ((uu - W / 2) ** 2 + (vv - H / 2) ** 2) / ((W / 2) ** 2 + (H / 2) ** 2)
        vignette = 1.0 - effects.vignetting * r2**1.5
        self.sensor_gain = (gain * vignette[..., None] * wb[None, None, :]).astype(np.float32)
        self.noise_bank = rng.standard_normal((2 * H, 2 * W, 3)).astype(np.float32)

    # -- static scene -------------------------------------------------------------------------

    def _render_static(self, furniture: list[FurnitureSpec]) -> None:
        cam, room = self.cam, self.room
        d_cam = np.stack([self.xn, self.yn, np.ones_like(self.xn)], axis=-1)
        d_w = (d_cam @ cam.R.astype(np.float32)).astype(np.float64)  # R.T @ d per pixel
        C = cam.centre_m
        size = np.array(room.size_m)
        with np.errstate(divide="ignore", invalid="ignore"):
            t_axes = np.where(d_w > 0, (size - C) / d_w, (0.0 - C) / d_w)
        t_axes[~np.isfinite(t_axes)] = np.inf
        axis = np.argmin(t_axes, axis=-1)
        t = np.take_along_axis(t_axes, axis[..., None], -1)[..., 0]
        P = C + t[..., None] * d_w
        normal = np.zeros_like(P)
        np.put_along_axis(
            normal, axis[..., None], -np.sign(np.take_along_axis(d_w, axis[..., None], -1)), -1
        )
        albedo = np.zeros_like(P, dtype=np.float32)
        cls = np.zeros(t.shape, dtype=np.uint8)
        is_floor = (axis == 2) & (d_w[..., 2] < 0)
        is_ceiling = (axis == 2) & (d_w[..., 2] > 0)
        is_wall = axis < 2
        albedo[is_floor] = self._floor_texture(P[is_floor])
        albedo[is_ceiling] = np.array([0.86, 0.87, 0.87], dtype=np.float32)
        albedo[is_wall] = self._wall_texture(P[is_wall], axis[is_wall], d_w[is_wall])
        if room.skin_panel:
            cls[is_wall & self._skin_panel(P, axis)] = int(MaskClass.SKIN_DISTRACTOR)
        for spec in furniture:
            for box in furniture_boxes(spec):
                tb, nb = ray_box_world(C, d_w, box)
                hit = tb < t
                t = np.where(hit, tb, t)
                normal[hit] = nb[hit]
                hit_xy = C[:2] + tb[hit][:, None] * d_w[hit][:, :2]
                grain = 0.92 + 0.08 * _value_noise(hit_xy[:, 0], hit_xy[:, 1], 0.03, 7)
                albedo[hit] = (box.albedo[None, :] * grain[:, None]).astype(np.float32)
                cls[hit] = box.mask_class
                is_floor &= ~hit
        P = C + t[..., None] * d_w
        shade = (
            AMBIENT + DIFFUSE * np.clip(normal @ light_direction(room), 0, None)
        ) * lamp_falloff(P, room)
        self.static_colour = (albedo * shade[..., None].astype(np.float32) * 255).astype(
            np.float32
        )
        # rays are (xn, yn, 1) in the camera frame, so the ray parameter is the camera depth
        self.static_depth = t.astype(np.float32)
        self.static_class = cls
        # coarse floor coordinates for the shadow pass
        step = 4
        self.shadow_step = step
        fxy = P[::step, ::step, :2].astype(np.float32)
        self.floor_coarse = fxy
        self.floor_coarse_mask = is_floor[::step, ::step]

    def _floor_texture(self, P: np.ndarray) -> np.ndarray:
        x, y = P[:, 0], P[:, 1]
        kind = self.room.floor
        if kind == "tiles":
            tile = 0.5
            ix, iy = np.floor(x / tile), np.floor(y / tile)
            base = np.array([0.60, 0.62, 0.63], dtype=np.float32)
            var = 0.92 + 0.12 * _hash01(ix.astype(np.int64), iy.astype(np.int64))
            fx, fy = x / tile - ix, y / tile - iy
            grout = np.minimum(np.minimum(fx, 1 - fx), np.minimum(fy, 1 - fy)) < 0.018
            speck = 0.94 + 0.1 * _value_noise(x, y, 0.04, 3)
            out = base[None, :] * (var * speck)[:, None]
            out[grout] *= 0.55
        elif kind == "wood":
            plank_w = 0.14
            iy = np.floor(y / plank_w)
            off = _hash01(iy.astype(np.int64)) * 1.5
            ix = np.floor((x + off) / 1.2)
            var = 0.8 + 0.25 * _hash01(ix.astype(np.int64), iy.astype(np.int64))
            grain = 0.85 + 0.15 * np.sin(x * 60 + 8 * _value_noise(x, y, 0.3, 5))
            base = np.array([0.22, 0.30, 0.42], dtype=np.float32)  # dark walnut (BGR)
            out = base[None, :] * (var * grain)[:, None]
            out[(y / plank_w - iy) < 0.03] *= 0.5
        else:
            base = np.array([0.42, 0.36, 0.33], dtype=np.float32)
            out = base[None, :] * (0.85 + 0.3 * _value_noise(x, y, 0.01, 9))[:, None]
        return out.astype(np.float32)

    def _wall_texture(self, P: np.ndarray, axis: np.ndarray, d_w: np.ndarray) -> np.ndarray:
        room = self.room
        wall = parse_rgb(tuple(room.wall_rgb), "room.wall_rgb").astype(np.float32)
        # each wall a slightly different tint, with low-frequency paint variation
        wall_id = axis * 2 + (d_w[np.arange(len(axis)), axis] > 0)
        tint = 0.94 + 0.06 * _hash01(wall_id.astype(np.int64))
        along = np.where(axis == 0, P[:, 1], P[:, 0])
        paint = 0.96 + 0.06 * _value_noise(along, P[:, 2], 0.6, 11)
        out = wall[None, :] * (tint * paint)[:, None]
        out[P[:, 2] < 0.10] = np.array([0.75, 0.76, 0.78], dtype=np.float32)
        X, Y, _ = room.size_m
        # a blue-grey door on the wall y = Y
        door = (
            (axis == 1)
            & (P[:, 1] > Y - 1e-6)
            & (np.abs(P[:, 0] - 0.7 * X) < 0.45)
            & (P[:, 2] < 2.05)
        )
        out[door] = np.array([0.55, 0.45, 0.38], dtype=np.float32)
        if room.poster:
            pu, pv = P[:, 1] - 0.45 * Y, P[:, 2] - 1.55
            poster = (axis == 0) & (P[:, 0] < 1e-6) & (np.abs(pu) < 0.5) & (np.abs(pv) < 0.35)
            cell = (np.floor((pu + 0.5) / 0.34) + 3 * np.floor((pv + 0.35) / 0.35)).astype(int)
            hues = np.array([0, 40, 100, 200, 280, 160], dtype=np.float32)
            hsv = np.zeros((len(hues), 1, 3), dtype=np.uint8)
            hsv[:, 0, 0] = hues / 2
            hsv[:, 0, 1:] = (200, 210)
            palette = cv2.cvtColor(hsv, cv2.COLOR_HSV2BGR)[:, 0].astype(np.float32) / 255
            out[poster] = palette[np.clip(cell[poster], 0, 5)]
        if room.skin_panel:
            out[self._skin_panel(P, axis)] = np.array([0.42, 0.56, 0.74], dtype=np.float32)
        return out.astype(np.float32)

    def _skin_panel(self, P: np.ndarray, axis: np.ndarray) -> np.ndarray:
        X, Y, _ = self.room.size_m
        return (
            (axis == 0)
            & (P[..., 0] > X - 1e-6)
            & (np.abs(P[..., 1] - 0.4 * Y) < 0.45)
            & (np.abs(P[..., 2] - 1.4) < 0.3)
        )

    # -- per frame ----------------------------------------------------------------------------

    def shadow_factor(self, casters_m: np.ndarray, strength: float) -> np.ndarray:
        """(H', W') floor darkening from soft blobs at ``casters_m`` (K, 3): x, y, weight."""
        if len(casters_m) == 0 or strength <= 0:
            return None
        xy = self.floor_coarse
        acc = np.zeros(xy.shape[:2], dtype=np.float32)
        for x, y, w in casters_m:
            d2 = (xy[..., 0] - np.float32(x)) ** 2 + (xy[..., 1] - np.float32(y)) ** 2
            acc += np.float32(w) * np.exp(d2 * np.float32(-1 / (2 * 0.2**2)))
        factor = 1.0 - strength * np.clip(acc, 0, 1)
        factor[~self.floor_coarse_mask] = 1.0
        return cv2.resize(factor, (self.canvas_w, self.canvas_h), interpolation=cv2.INTER_LINEAR)

    def render(
        self,
        prims: list[Ellipsoid],
        shadow_casters: np.ndarray,
        illumination: float,
        noise_rng: np.random.Generator,
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Render one frame.

        Returns
        -------
        image : (H, W, 3) uint8 BGR -- the sensor's output (before compression)
        winner : (H', W') int16 canvas -- index of the primitive shown, -1 for static scene
        full_area : (P,) int -- canvas pixels each primitive covers when nothing occludes it
        boxes : (P, 4) int -- canvas bounding box (row0, row1, col0, col1) of each primitive
        """
        colour = self.static_colour.copy()
        shadow = self.shadow_factor(shadow_casters, self.effects.shadows)
        if shadow is not None:
            colour *= shadow[..., None]
        depth = self.static_depth.copy()
        winner = np.full(depth.shape, -1, dtype=np.int16)
        full_area = np.zeros(len(prims), dtype=np.int64)
        boxes = np.zeros((len(prims), 4), dtype=np.int64)
        R, tvec = self.cam.R, self.cam.t
        for k, p in enumerate(prims):
            c = R @ p.centre_m + tvec
            axes = R @ p.axes
            if c[2] < NEAR_M + p.radii_m.max():
                continue
            corners = (c[:, None] + (axes * p.radii_m) @ _CORNERS.T).T
            if (corners[:, 2] <= NEAR_M).any():
                continue
            u = corners[:, 0] / corners[:, 2] * self.fx + self.cx
            v = corners[:, 1] / corners[:, 2] * self.fy + self.cy
            j0, j1 = max(int(u.min()), 0), min(int(np.ceil(u.max())) + 1, self.canvas_w)
            i0, i1 = max(int(v.min()), 0), min(int(np.ceil(v.max())) + 1, self.canvas_h)
            if j0 >= j1 or i0 >= i1:
                continue
            boxes[k] = i0, i1, j0, j1
            xn, yn = self.xn[i0:i1, j0:j1], self.yn[i0:i1, j0:j1]
            if p.kind == 0:
                t, n0, n1, n2, hit = _ray_ellipsoid(xn, yn, c, axes, p.radii_m)
            else:
                t, n0, n1, n2, hit = _ray_box(xn, yn, c, axes, p.radii_m)
            full_area[k] = int(np.count_nonzero(hit))
            dsub = depth[i0:i1, j0:j1]
            hit &= t < dsub
            if not hit.any():
                continue
            L = self.light_cam
            rn = np.sqrt(xn * xn + yn * yn + 1)
            lambert = np.maximum(n0 * L[0] + n1 * L[1] + n2 * L[2], 0)
            fill = np.maximum(-(n0 * xn + n1 * yn + n2) / rn, 0)
            shade = (AMBIENT + DIFFUSE * lambert + FILL * fill) * np.float32(
                lamp_falloff(p.centre_m, self.room) * 255
            )
            csub = colour[i0:i1, j0:j1]
            csub[hit] = shade[hit][:, None] * p.albedo.astype(np.float32)[None, :]
            dsub[hit] = t[hit]
            winner[i0:i1, j0:j1][hit] = k
        real = cv2.remap(
            colour, self.map_x, self.map_y, cv2.INTER_LINEAR, borderMode=cv2.BORDER_REPLICATE
        )
        real *= self.sensor_gain
        real *= np.float32(illumination)
        H, W = real.shape[:2]
        oy, ox = noise_rng.integers(0, H), noise_rng.integers(0, W)
        noise = self.noise_bank[oy : oy + H, ox : ox + W]
        sigma = np.sqrt(
            np.float32(self.effects.noise_sigma**2)
            + np.float32(self.effects.shot_noise) * np.maximum(real, 0)
        )
        real += noise * sigma
        np.clip(real, 0, 255, out=real)
        return real.astype(np.uint8), winner, full_area, boxes

    def distort_labels(self, labels: np.ndarray) -> np.ndarray:
        """Warp a canvas label image (uint8, any channels) to the real image, nearest."""
        return cv2.remap(
            labels, self.map_x, self.map_y, cv2.INTER_NEAREST, borderMode=cv2.BORDER_REPLICATE
        )

    def canvas_pixel(self, points_m: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Canvas (col, row) integer pixels of world points and a validity mask."""
        pc = points_m @ self.cam.R.T + self.cam.t
        z = pc[:, 2]
        with np.errstate(divide="ignore", invalid="ignore"):
            u = np.round(pc[:, 0] / z * self.fx + self.cx)
            v = np.round(pc[:, 1] / z * self.fy + self.cy)
        ok = (z > NEAR_M) & (u >= 0) & (v >= 0) & (u < self.canvas_w) & (v < self.canvas_h)
        return np.column_stack([np.where(ok, u, 0), np.where(ok, v, 0)]).astype(int), ok


_CORNERS = np.array(
    [[sx, sy, sz] for sx in (-1, 1) for sy in (-1, 1) for sz in (-1, 1)], dtype=np.float64
)


def _ray_ellipsoid(xn, yn, c, axes, radii):
    """Nearest intersection of rays (xn, yn, 1) from the camera with an ellipsoid.

    An ellipsoid is |A (x - c)| = 1 with A = diag(1/r) axes^T; along x = t d this is the
    quadratic a t^2 - 2 b t + cc = 0, a = |A d|^2, b = (A d).(A c), cc = |A c|^2 - 1.
    The outward normal is A^T A (x - c).
    """
    A = (axes / radii).T.astype(np.float32)
    Ac = (A @ c).astype(np.float32)
    Ad0 = A[0, 0] * xn + A[0, 1] * yn + A[0, 2]
    Ad1 = A[1, 0] * xn + A[1, 1] * yn + A[1, 2]
    Ad2 = A[2, 0] * xn + A[2, 1] * yn + A[2, 2]
    a = Ad0 * Ad0 + Ad1 * Ad1 + Ad2 * Ad2
    b = Ad0 * Ac[0] + Ad1 * Ac[1] + Ad2 * Ac[2]
    cc = np.float32(Ac @ Ac - 1)
    disc = b * b - a * cc
    hit = disc > 0
    t = (b - np.sqrt(np.maximum(disc, 0))) / a
    hit &= t > NEAR_M
    y0, y1, y2 = t * Ad0 - Ac[0], t * Ad1 - Ac[1], t * Ad2 - Ac[2]
    n0 = A[0, 0] * y0 + A[1, 0] * y1 + A[2, 0] * y2
    n1 = A[0, 1] * y0 + A[1, 1] * y1 + A[2, 1] * y2
    n2 = A[0, 2] * y0 + A[1, 2] * y1 + A[2, 2] * y2
    inv = 1 / np.maximum(np.sqrt(n0 * n0 + n1 * n1 + n2 * n2), 1e-9)
    return t, n0 * inv, n1 * inv, n2 * inv, hit


def _ray_box(xn, yn, c, axes, half):
    """Nearest intersection of rays (xn, yn, 1) with an oriented box (slab method)."""
    B = axes.T.astype(np.float32)  # rows: box axes in camera coordinates
    o = -(B @ c).astype(np.float32)
    tnear = np.full(xn.shape, -np.inf, dtype=np.float32)
    tfar = np.full(xn.shape, np.inf, dtype=np.float32)
    near_axis = np.zeros(xn.shape, dtype=np.int8)
    near_sign = np.zeros(xn.shape, dtype=np.float32)
    with np.errstate(divide="ignore", invalid="ignore"):
        for i in range(3):
            d = B[i, 0] * xn + B[i, 1] * yn + B[i, 2]
            t1 = (-np.float32(half[i]) - o[i]) / d
            t2 = (np.float32(half[i]) - o[i]) / d
            lo, hi = np.minimum(t1, t2), np.maximum(t1, t2)
            lo = np.nan_to_num(lo, nan=-np.inf)
            hi = np.nan_to_num(hi, nan=np.inf)
            better = lo > tnear
            tnear = np.where(better, lo, tnear)
            near_axis = np.where(better, i, near_axis)
            near_sign = np.where(better, -np.sign(d), near_sign)
            tfar = np.minimum(tfar, hi)
    hit = (tnear < tfar) & (tnear > NEAR_M)
    n = [np.zeros_like(xn) for _ in range(3)]
    for i in range(3):
        sel = (near_axis == i) * near_sign
        for j in range(3):
            n[j] = n[j] + sel * B[i, j]
    return tnear, n[0], n[1], n[2], hit


def ray_box_world(C: np.ndarray, d_w: np.ndarray, box: StaticBox) -> tuple[np.ndarray, np.ndarray]:
    """Ray parameter (inf where missed) and world normals of rays C + t d_w against a box."""
    c, s = np.cos(box.yaw_rad), np.sin(box.yaw_rad)
    Rb = np.array([[c, -s, 0], [s, c, 0], [0, 0, 1.0]])  # box axes (columns) in world
    o = (C - box.centre_m) @ Rb
    d = d_w @ Rb
    with np.errstate(divide="ignore", invalid="ignore"):
        t1 = (-box.half_m - o) / d
        t2 = (box.half_m - o) / d
    lo, hi = (
        np.nan_to_num(np.minimum(t1, t2), nan=-np.inf),
        np.nan_to_num(np.maximum(t1, t2), nan=np.inf),
    )
    axis = np.argmax(lo, axis=-1)
    tnear = np.take_along_axis(lo, axis[..., None], -1)[..., 0]
    tfar = hi.min(axis=-1)
    hit = (tnear < tfar) & (tnear > 0)
    sign = -np.sign(np.take_along_axis(d, axis[..., None], -1)[..., 0])
    normal = Rb.T[axis] * sign[..., None]
    return np.where(hit, tnear, np.inf), normal
