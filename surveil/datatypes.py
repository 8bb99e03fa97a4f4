"""Data passed between stages and to output files.

Conventions (repeated in docstrings where they matter):

- SI units inside maths: metres, seconds, radians; names carry units (``_m``, ``_s``, ``_px``,
  ``_deg``, ``_ns``). Timestamps that cross a stage or reach a file are integer nanoseconds on
  the recording clock (``_ns``). Hue is in degrees ``[0, 360)``.
- World frame: right-handed, Z up, floor at Z = 0. Camera frames as OpenCV (x right, y down,
  z forward). Transforms are named ``a_from_b``.
- Images are indexed ``[row, col]``, uint8 BGR as OpenCV delivers them; pixel coordinates are
  ``(u, v) = (col, row)`` floats. Masks are ``bool``.
- Struct-of-arrays: one array per attribute. "Nothing found" is an empty array of the right
  shape, never ``None``.
"""

from __future__ import annotations

import enum
import re
from collections.abc import Mapping
from dataclasses import dataclass, field

import numpy as np

from surveil.validate import readonly, require_shape


class Limb(enum.IntEnum):
    """Limb type of a target; the integer is the ``limb`` field of ``/targets/points``."""

    HEAD = 0
    LEFT_HAND = 1
    RIGHT_HAND = 2
    UNKNOWN = 255

    @property
    def key(self) -> str:
        """The label suffix: ``head``, ``left_hand``, ``right_hand`` (``unknown`` otherwise)."""
        return self.name.lower()

    @property
    def is_hand(self) -> bool:
        return self in (Limb.LEFT_HAND, Limb.RIGHT_HAND)

    @classmethod
    def from_key(cls, key: str) -> Limb:
        try:
            return cls[key.upper()]
        except KeyError:
            raise ValueError(
                f"unknown limb {key!r}; expected head, left_hand or right_hand"
            ) from None


class Phase(enum.Enum):
    """Tracker state (paper 004 Fig. 1). ``code`` is the ``state`` field of
    ``/targets/points``; uninitialised trackers are never written."""

    UNINITIALISED = "uninitialised"
    UNLABELLED = "unlabelled"
    NORMAL = "normal"
    COMBINED = "combined"
    LOST = "lost"

    @property
    def code(self) -> int:
        return {"unlabelled": 0, "normal": 1, "combined": 2, "lost": 3}.get(self.value, 255)


LABEL_RE = re.compile(
    r"^(?:p(?P<person>[1-9][0-9]*)/(?P<limb>head|left_hand|right_hand)"
    r"|t(?P<tracker>[0-9]+))$"
)


def make_label(person: int, limb: Limb, tracker_id: int) -> str:
    """The target label of formats.md: ``p<N>/<limb>`` when labelled, else ``t<tracker>``.

    >>> make_label(2, Limb.LEFT_HAND, 7), make_label(0, Limb.UNKNOWN, 7)
    ('p2/left_hand', 't7')
    """
    if person > 0 and limb is not Limb.UNKNOWN:
        return f"p{person}/{limb.key}"
    return f"t{tracker_id}"


def parse_label(label: str) -> tuple[int, Limb]:
    """``'p2/left_hand'`` -> ``(2, Limb.LEFT_HAND)``; ``'t7'`` -> ``(0, Limb.UNKNOWN)``.

    >>> parse_label("p2/left_hand")
    (2, <Limb.LEFT_HAND: 1>)
    """
    m = LABEL_RE.match(label)
    if m is None:
        raise ValueError(
            f"target label must look like 'p1/head', 'p2/left_hand' or 't5', got {label!r}"
        )
    if m["tracker"] is not None:
        return 0, Limb.UNKNOWN
    return int(m["person"]), Limb.from_key(m["limb"])


@dataclass(frozen=True, slots=True)
class FrameSet:
    """Synchronised frames of one instant.

    index : int
        Frame-set number, 0-based, on the recording's nominal grid.
    t_ns : int
        Time of the set on the recording clock, ns from t = 0.
    images : Mapping[str, (H, W, 3) uint8 BGR]
        One image per camera that has a frame within half a period of ``t_ns``; a camera
        with a dropped or missing frame is absent.
    frame_t_ns : Mapping[str, int]
        The timestamp of each camera's frame (may differ from ``t_ns`` by jitter).
    """

    index: int
    t_ns: int
    images: Mapping[str, np.ndarray]
    frame_t_ns: Mapping[str, int] = field(default_factory=dict)

    def __post_init__(self) -> None:
        for cam, img in self.images.items():
            require_shape(f"images[{cam!r}]", img, (None, None, 3), np.uint8)


@dataclass(frozen=True, slots=True)
class TargetSnapshot:
    """A tracked target at one instant, as written to ``/targets``.

    target_id : int   tracker id (``tracker`` metadata)
    person : int      person number N of ``pN`` (0 = not assigned)
    limb : Limb
    phase : Phase
    mean_m : (3,) float64, world frame, metres
    cov_m2 : (3, 3) float64, m^2
    carried_hue_deg : float | None
    """

    target_id: int
    person: int
    limb: Limb
    phase: Phase
    mean_m: np.ndarray
    cov_m2: np.ndarray = field(default_factory=lambda: np.zeros((3, 3)))
    carried_hue_deg: float | None = None

    def __post_init__(self) -> None:
        mean = np.asarray(self.mean_m, dtype=np.float64)
        cov = np.asarray(self.cov_m2, dtype=np.float64)
        require_shape("mean_m", mean, (3,), np.floating)
        require_shape("cov_m2", cov, (3, 3), np.floating)
        readonly(mean, cov)
        object.__setattr__(self, "mean_m", mean)
        object.__setattr__(self, "cov_m2", cov)

    @property
    def label(self) -> str:
        return make_label(self.person, self.limb, self.target_id)


@dataclass(frozen=True, slots=True)
class CandidateSet:
    """3D candidate points of one frame set (paper 004 sections 5.1 and 6.3).

    points_m : (K, 3) float64, world frame, metres
    prior : (K,) float64, p(Z) in [0, 1]
    half_gap_m : (K,) float64, optional -- d, half the shortest distance between the two
        lines of sight (eq. 24)
    cam_pairs : (K, 2) int, optional -- indices (into the rig's camera order) of the two views;
        -1 for points no camera pair made (the arm model's hands, ``surveil.armpose.feed``)
    blob_pairs : (K, 2) int, optional -- blob indices in those two views (-1 likewise)
    rescued : (K,) bool, optional -- kept only because a tracked target was expected there
        (``surveil.recon.candidates.rescue_expected``); explaining away dropped it
    head_only : (K,) bool, optional -- evidence of a head only (the silhouettes' crowns,
        ``surveil.recon.crowns``): the tracker lets no hand's tracker take it
    views : (K,) int, optional -- how many cameras support the point (a blob within
        ``support_radius_px`` of its projection, its own two included;
        ``surveil.recon.candidates.view_support``; None when explaining away is off)
    """

    points_m: np.ndarray
    prior: np.ndarray
    half_gap_m: np.ndarray | None = None
    cam_pairs: np.ndarray | None = None
    blob_pairs: np.ndarray | None = None
    rescued: np.ndarray | None = None
    head_only: np.ndarray | None = None
    views: np.ndarray | None = None

    def __post_init__(self) -> None:
        k = len(self.points_m)
        require_shape("points_m", self.points_m, (None, 3), np.floating)
        require_shape("prior", self.prior, (k,), np.floating)
        readonly(self.points_m, self.prior)
        for name, shape, kind in (
            ("half_gap_m", (k,), np.floating),
            ("cam_pairs", (k, 2), np.integer),
            ("blob_pairs", (k, 2), np.integer),
            ("rescued", (k,), np.bool_),
            ("head_only", (k,), np.bool_),
            ("views", (k,), np.integer),
        ):
            value = getattr(self, name)
            if value is not None:
                require_shape(name, value, shape, kind)
                readonly(value)

    @classmethod
    def empty(cls) -> CandidateSet:
        return cls(np.zeros((0, 3)), np.zeros(0))

    def with_points(self, points_m: np.ndarray, prior: float, views: np.ndarray) -> CandidateSet:
        """This set followed by ``points_m`` (E, 3) that no camera pair made (a stage's
        own evidence): prior ``prior``, ``views`` (E,) the views behind each; their
        ``cam_pairs`` and ``blob_pairs`` rows are -1, ``half_gap_m`` NaN, ``rescued`` and
        ``head_only`` false."""
        e = len(points_m)
        if not e:
            return self

        def rows(a: np.ndarray | None, fill: object) -> np.ndarray | None:
            if a is None:
                return None
            return np.concatenate([a, np.full((e, *a.shape[1:]), fill, a.dtype)])

        n = len(self.points_m)
        return CandidateSet(
            points_m=np.concatenate([self.points_m, points_m]),
            prior=np.concatenate([self.prior, np.full(e, prior)]),
            half_gap_m=rows(self.half_gap_m, np.nan),
            cam_pairs=rows(self.cam_pairs, -1),
            blob_pairs=rows(self.blob_pairs, -1),
            rescued=rows(self.rescued, False),
            head_only=rows(self.head_only, False),
            views=np.concatenate(
                [np.full(n, 2, np.int64) if self.views is None else self.views, views]
            ).astype(np.int64),
        )


@dataclass(frozen=True, slots=True)
class ActivityEvent:
    """A recognised (or ground-truth) activity.

    Times are ns on the recording clock. ``actors`` are target labels (``p1/right_hand``),
    ``persons`` person labels (``p1``). ``from_actor``/``to_actor`` are set for exchanges.
    ``rule`` is ``<rules file>:<rule name>`` (``ground_truth`` for annotations).
    """

    activity: str
    start_ns: int
    climax_ns: int
    end_ns: int
    actors: tuple[str, ...]
    persons: tuple[str, ...]
    rule: str
    confidence: float = 1.0
    object_hue_deg: float | None = None
    from_actor: str | None = None
    to_actor: str | None = None
    object_name: str | None = None

    def __post_init__(self) -> None:
        if not self.start_ns <= self.climax_ns <= self.end_ns:
            raise ValueError(
                f"event {self.activity}: need start_ns <= climax_ns <= end_ns, got "
                f"{self.start_ns}, {self.climax_ns}, {self.end_ns}"
            )
        if not 0.0 <= self.confidence <= 1.0:
            raise ValueError(
                f"event {self.activity}: confidence must be in [0, 1], got {self.confidence}"
            )
        for a in self.actors:
            parse_label(a)


@dataclass(frozen=True, slots=True)
class Silhouettes:
    """Person silhouettes of one camera frame (foreground connected components).

    labels : (H, W) int32 -- 0 background, s = 1..n for component s
    top_v_px, bottom_v_px : (n,) float64 -- first and last image row of each component
    dist_outside_px : (H, W) float32 -- distance of every pixel to the nearest silhouette
        pixel, 0 inside a silhouette (for the silhouette prior p_b, paper 004 eq. 27); in a
        run clipped at ``surveil.pipeline.silhouette_distance_cap_px`` (min(distance, cap))
    changed : (H, W) bool or None -- pixels the background model found unlike the background
        (foreground or shadow) before the morphological clean-up; None when not known. The
        clean-up's closing fills gaps between limbs with background, which ``changed`` tells
        apart.
    background_edges : (H, W) float32 or None -- gradient magnitude (3x3 Sobel of the grey
        image) of the background model's image, recomputed every few frames; None during the
        learning phase or when not asked for. Edges of the empty scene: the blob stage tells
        revealed background (an object taken away) from things in front of it with them.
    centres_px : (n, 2) float64 or None -- centre of mass (u, v) of each component; None when
        not known. The blob stage places a silhouette's shoulder point on its column (and
        ``SHOULDER_DROP_REL`` of the height below ``top_v_px``) to tell a bare forearm's
        hand end from its elbow end.
    boxes_px : (n, 4) int32 or None -- x, y, width, height of a box holding each component
        (its bounding box, or one a little larger); None when not known (then read from
        ``labels``). Skin and blobs are computed inside these boxes only (:meth:`boxes`).
    foreground : (H, W) bool or None -- pixels the background model called foreground
        (not shadow) before the clean-up; None when not known. The blob stage's foreground
        share test: skin-coloured scenery inside a silhouette (a wooden table behind a hand)
        is mostly not foreground, a hand or face mostly is.
    """

    labels: np.ndarray
    top_v_px: np.ndarray
    bottom_v_px: np.ndarray
    dist_outside_px: np.ndarray
    changed: np.ndarray | None = None
    background_edges: np.ndarray | None = None
    centres_px: np.ndarray | None = None
    boxes_px: np.ndarray | None = None
    foreground: np.ndarray | None = None

    def __post_init__(self) -> None:
        require_shape("labels", self.labels, (None, None), np.integer)
        n = len(self.top_v_px)
        if self.boxes_px is not None:
            require_shape("boxes_px", self.boxes_px, (n, 4), np.integer)
            readonly(self.boxes_px)
        require_shape("top_v_px", self.top_v_px, (n,), np.floating)
        require_shape("bottom_v_px", self.bottom_v_px, (n,), np.floating)
        require_shape("dist_outside_px", self.dist_outside_px, self.labels.shape, np.floating)
        if self.centres_px is not None:
            require_shape("centres_px", self.centres_px, (n, 2), np.floating)
            readonly(self.centres_px)
        readonly(self.labels, self.top_v_px, self.bottom_v_px, self.dist_outside_px)
        for name in ("changed", "foreground"):
            mask = getattr(self, name)
            if mask is not None:
                require_shape(name, mask, self.labels.shape, np.bool_)
                readonly(mask)
        if self.background_edges is not None:
            require_shape("background_edges", self.background_edges, self.labels.shape, np.float32)
            readonly(self.background_edges)

    @property
    def n(self) -> int:
        return len(self.top_v_px)

    @property
    def mask(self) -> np.ndarray:
        """(H, W) bool foreground."""
        return self.labels > 0

    def boxes(self, margin_px: int) -> np.ndarray:
        """(k, 4) int64 x0, y0, x1, y1 (end exclusive) of boxes that hold every silhouette
        pixel and everything within ``margin_px`` of one, clipped to the frame; k = 0 when
        there is no silhouette. One box per component when ``boxes_px`` is known, else one
        around them all.

        >>> lab = np.zeros((10, 12), np.int32); lab[2:5, 3:6] = 1
        >>> s = Silhouettes(lab, np.array([2.0]), np.array([4.0]), np.zeros((10, 12), np.float32))
        >>> s.boxes(1).tolist()
        [[2, 1, 7, 6]]
        """
        h, w = self.labels.shape
        if self.n == 0:
            return np.zeros((0, 4), np.int64)
        if self.boxes_px is not None:
            x, y, bw, bh = self.boxes_px.astype(np.int64).T
        else:
            fg = self.labels > 0
            rows, cols = np.flatnonzero(fg.any(axis=1)), np.flatnonzero(fg.any(axis=0))
            x, y = cols[:1].astype(np.int64), rows[:1].astype(np.int64)
            bw, bh = cols[-1:] + 1 - x, rows[-1:] + 1 - y
        out = np.stack(
            [
                np.clip(x - margin_px, 0, w),
                np.clip(y - margin_px, 0, h),
                np.clip(x + bw + margin_px, 0, w),
                np.clip(y + bh + margin_px, 0, h),
            ],
            axis=1,
        )
        return out[(out[:, 2] > out[:, 0]) & (out[:, 3] > out[:, 1])]

    def region(self, margin_px: int) -> tuple[slice, slice] | None:
        """(rows, cols) of the one box around :meth:`boxes` (``margin_px``), or None when
        there is no silhouette."""
        b = self.boxes(margin_px)
        if len(b) == 0:
            return None
        return slice(int(b[:, 1].min()), int(b[:, 3].max())), slice(
            int(b[:, 0].min()), int(b[:, 2].max())
        )

    def crop(self, region: tuple[slice, slice]) -> Silhouettes:
        """These silhouettes seen through ``region`` (rows, cols): arrays cut to it, rows,
        centres and boxes moved to its coordinates."""
        rows, cols = region
        y0, x0 = rows.start, cols.start
        shift = np.array([x0, y0])

        def cut(a: np.ndarray | None) -> np.ndarray | None:
            return None if a is None else a[rows, cols]

        return Silhouettes(
            self.labels[rows, cols],
            self.top_v_px - y0,
            self.bottom_v_px - y0,
            self.dist_outside_px[rows, cols],
            cut(self.changed),
            cut(self.background_edges),
            None if self.centres_px is None else self.centres_px - shift,
            None
            if self.boxes_px is None
            else np.column_stack([self.boxes_px[:, :2] - shift, self.boxes_px[:, 2:]]).astype(
                np.int32
            ),
            cut(self.foreground),
        )


@dataclass(frozen=True, slots=True)
class BlobSet:
    """Skin blobs of one camera frame, largest first (paper 004 section 6.2).

    centroids_px : (B, 2) float64 -- the blob's point (u, v): its centre of mass, or the
        centre of its hand end when it is a bare forearm (docs/blobs.md, "Bare forearms")
    areas_px : (B,) int64
    bboxes_px : (B, 4) int32 -- x, y, width, height
    silhouette : (B,) int32 -- label of the silhouette component holding the blob (0 none)
    rel_v : (B,) float64 -- (v - top) / (bottom - top) of the blob's silhouette: 0 at the top
    labels : (H, W) int32 -- 0 none, i + 1 for blob i
    foreground_share : (B,) float64 or None -- share of the blob's pixels that the background
        model called foreground (not shadow, before the clean-up); None when not measured.
        Skin-coloured scenery that a silhouette took in is mostly background, a hand or face
        mostly is not (docs/blobs.md, "Foreground share")
    restored : (B,) bool or None -- True for a blob that the opening would have shrunk below
        a blob's size and ``BlobConfig.open_keeps_isolated`` kept whole (a hand seen edge-on,
        or a fringe of colour along a fold); None when no blob was restored or the setting is
        off
    hand_px : (B, 2) float64 or None -- where the pull of reported hand points
        (:mod:`surveil.tracking.blob_pull`) takes each blob's hand to be: the hand end of a
        blob taken for a bare forearm, the centroid of any other. Kept only with
        ``BlobConfig.arm_hand_end = 'report'``; None otherwise (the pull then uses
        ``centroids_px``)
    """

    centroids_px: np.ndarray
    areas_px: np.ndarray
    bboxes_px: np.ndarray
    silhouette: np.ndarray
    rel_v: np.ndarray
    labels: np.ndarray
    foreground_share: np.ndarray | None = None
    restored: np.ndarray | None = None
    hand_px: np.ndarray | None = None

    def __post_init__(self) -> None:
        n = len(self.centroids_px)
        require_shape("centroids_px", self.centroids_px, (n, 2), np.floating)
        require_shape("areas_px", self.areas_px, (n,), np.integer)
        require_shape("bboxes_px", self.bboxes_px, (n, 4), np.integer)
        require_shape("silhouette", self.silhouette, (n,), np.integer)
        require_shape("rel_v", self.rel_v, (n,), np.floating)
        require_shape("labels", self.labels, (None, None), np.integer)
        readonly(
            self.centroids_px,
            self.areas_px,
            self.bboxes_px,
            self.silhouette,
            self.rel_v,
            self.labels,
        )
        if self.foreground_share is not None:
            require_shape("foreground_share", self.foreground_share, (n,), np.floating)
            readonly(self.foreground_share)
        if self.restored is not None:
            require_shape("restored", self.restored, (n,), np.bool_)
            readonly(self.restored)
        if self.hand_px is not None:
            require_shape("hand_px", self.hand_px, (n, 2), np.floating)
            readonly(self.hand_px)

    def __len__(self) -> int:
        return len(self.centroids_px)

    @classmethod
    def empty(cls, shape: tuple[int, int]) -> BlobSet:
        """No blobs in a frame of ``shape`` (H, W)."""
        return cls(
            np.zeros((0, 2)),
            np.zeros(0, np.int64),
            np.zeros((0, 4), np.int32),
            np.zeros(0, np.int32),
            np.zeros(0),
            np.zeros(shape, np.int32),
        )


@dataclass(frozen=True, slots=True)
class CameraObservation:
    """Everything the per-camera stage found in one frame: silhouettes, skin, blobs, and the
    silhouettes' crowns.

    crowns_px : (C, 2) float64 or None -- (u, v) of the crowns (heads' tops) on the
        silhouettes' top edges (:func:`surveil.recon.crowns.silhouette_crowns`); None when not
        looked for (the candidate stage then finds them itself)
    """

    camera: str
    silhouettes: Silhouettes
    skin: np.ndarray  # (H, W) bool skin pixels (whole frame, before the silhouette mask)
    blobs: BlobSet
    crowns_px: np.ndarray | None = None

    def __post_init__(self) -> None:
        if self.crowns_px is not None:
            require_shape("crowns_px", self.crowns_px, (None, 2), np.floating)


@dataclass(frozen=True, slots=True)
class Transition:
    """One tracker's phase change (paper 004 Fig. 1), timestamped for the later stages.

    The activity stage reads coincidence (``new is COMBINED``: the climax) and separation
    (``old is COMBINED``) moments from these.

    t_ns : int -- time of the frame set in which the change happened, ns
    target_id : int -- the tracker that changed
    old, new : Phase
    label : str -- the tracker's label *before* the change (``p1/right_hand`` or ``t7``)
    position_m : (3,) float64 -- its estimate at the change, world frame, metres
    partner_id : int | None -- for joins and separations, the other tracker involved
    partner_label : str | None -- that tracker's label before the change
    met : bool -- for separations: False when the tracker found that the pair's targets never
        met (the join is revoked: no coincidence happened; docs/tracking.md, "never met")
    """

    t_ns: int
    target_id: int
    old: Phase
    new: Phase
    label: str
    position_m: np.ndarray
    partner_id: int | None = None
    partner_label: str | None = None
    met: bool = True

    def __post_init__(self) -> None:
        pos = np.asarray(self.position_m, dtype=np.float64)
        require_shape("position_m", pos, (3,), np.floating)
        readonly(pos)
        object.__setattr__(self, "position_m", pos)


@dataclass(frozen=True, slots=True)
class TrackFrame:
    """Output of the tracking stage for one frame set.

    t_ns : int
    targets : every live tracker (not uninitialised), in tracker-id order
    transitions : phase changes that happened in this step
    particles_m : (N, 3) float32, optional -- all particles of all trackers (for review)
    particle_owner : (N,) int32, optional -- the tracker id of each particle
    """

    t_ns: int
    targets: tuple[TargetSnapshot, ...]
    transitions: tuple[Transition, ...] = ()
    particles_m: np.ndarray | None = None
    particle_owner: np.ndarray | None = None


@dataclass(frozen=True, slots=True)
class CarryEstimate:
    """What one hand carries at one instant (paper 004 sections 7.2-7.3).

    target_id : int -- the hand's tracker
    label : str -- its label (``p1/right_hand``)
    t_ns : int
    carrying : bool
    hue_deg : float | None -- hue of the strongest object mode, degrees [0, 360)
    confidence : float -- 0..1
    hue_pdf : (B,) float64 -- fused, normalised hue distribution of the hand's region
        (B bins over [0, 360)), after skin (and optionally clothing) removal
    since_ns : int | None -- time of the oldest sample in the fused window (None: no
        samples); a later stage can tell whether the estimate still holds evidence from
        before a given moment
    """

    target_id: int
    label: str
    t_ns: int
    carrying: bool
    hue_deg: float | None
    confidence: float
    hue_pdf: np.ndarray = field(default_factory=lambda: np.zeros(0))
    since_ns: int | None = None


@dataclass(frozen=True, slots=True)
class ArmPose:
    """One person's arms at one instant, from the arm model (docs/armpose.md).

    person : person number N of the head's label ``pN``
    facing_rad : body facing phi (0 = +X, counter-clockwise)
    facing_belief : the facing HMM's probability of its most likely level
    shoulders_m, elbows_m, hands_m : (2, 3) float64 -- left arm, right arm; world, metres
    n_views : cameras that took part
    """

    t_ns: int
    person: int
    facing_rad: float
    facing_belief: float
    shoulders_m: np.ndarray
    elbows_m: np.ndarray
    hands_m: np.ndarray
    n_views: int

    def __post_init__(self) -> None:
        for name in ("shoulders_m", "elbows_m", "hands_m"):
            require_shape(name, getattr(self, name), (2, 3), np.floating)
            readonly(getattr(self, name))


@dataclass(frozen=True, slots=True)
class FrameResult:
    """Everything the output sinks (MCAP, Rerun) need for one processed frame set.

    frameset : the input images and times
    observations : per camera that had a frame: silhouettes, skin, blobs
    candidates : the 3D candidate points
    track : tracker output (targets, transitions, optional particles)
    carry : per hand tracker id, what it carries (only hands the carry stage analysed)
    events : activities decided in this step (their climax may lie earlier)
    arms : the arm trackers' poses (empty when they are off)
    timings_ms : stage name -> milliseconds spent on this frame set
    """

    frameset: FrameSet
    observations: Mapping[str, CameraObservation]
    candidates: CandidateSet
    track: TrackFrame
    carry: Mapping[int, CarryEstimate] = field(default_factory=dict)
    events: tuple[ActivityEvent, ...] = ()
    arms: tuple[ArmPose, ...] = ()
    timings_ms: Mapping[str, float] = field(default_factory=dict)
