"""The review layout, built from the camera list: 3D view large on the left, the cameras in a
grid on the right, the event log, tracker states and carry confidence below."""

from __future__ import annotations

from collections.abc import Sequence

import rerun as rr
import rerun.blueprint as rrb

from surveil.viz import paths

#: True when this rerun-sdk has state lanes (``StateChange`` + ``StateTimelineView``).
HAS_STATE_LANES = hasattr(rr, "StateChange") and hasattr(rrb, "StateTimelineView")


def _event_columns() -> rrb.TextLogColumns | None:
    """Only the message column: each event line starts with its climax time already."""
    try:
        return rrb.TextLogColumns(timeline_columns=[], text_log_columns=["body"])
    except (TypeError, ValueError):  # an unstable blueprint type; the default columns do
        return None


def camera_view(cam: str) -> rrb.Spatial2DView:
    """A 2D view of one camera: its image, blobs, silhouettes and projected targets."""
    return rrb.Spatial2DView(name=cam, origin=paths.camera_path(cam), contents="$origin/**")


def world_view(
    cam_names: Sequence[str], eye: tuple[Sequence[float], Sequence[float]] | None = None
) -> rrb.Spatial3DView:
    """The 3D view: floor, camera frusta, candidates, targets. What is drawn in the image plane
    of each camera (frame, blobs, projected targets) is left out of the 3D view (it would cover
    the frusta); it is in the camera views.

    eye : (position, look target) of the initial viewpoint, world frame, metres; Z is up.
    """
    controls = None
    if eye is not None:
        controls = rrb.EyeControls3D(
            position=[float(v) for v in eye[0]],
            look_target=[float(v) for v in eye[1]],
            eye_up=[0.0, 0.0, 1.0],
        )
    return rrb.Spatial3DView(
        name="3D",
        origin=paths.WORLD,
        contents=[f"{paths.WORLD}/**"]
        + [f"- {p}" for c in cam_names for p in paths.camera_overlay_paths(c)],
        line_grid=False,
        eye_controls=controls,
    )


def build_blueprint(
    cam_names: Sequence[str],
    *,
    eye: tuple[Sequence[float], Sequence[float]] | None = None,
    collapse_panels: bool = True,
) -> rrb.Blueprint:
    """The review blueprint for these cameras (in this order).

    Parameters
    ----------
    cam_names : camera names, as in the rig.
    eye : initial 3D viewpoint (position, look target), world frame, metres.
    collapse_panels : hide the blueprint and selection side panels (more room for views).
    """
    cams = [camera_view(c) for c in cam_names]
    n_cols = 1 if len(cams) <= 2 else 2
    state_view: rrb.View
    if HAS_STATE_LANES:
        state_view = rrb.StateTimelineView(name="Tracker states", origin=paths.STATES)
    else:
        state_view = rrb.TimeSeriesView(name="Tracker states", origin=paths.STATES)
    bottom = rrb.Horizontal(
        rrb.TextLogView(name="Events", origin=paths.EVENTS, columns=_event_columns()),
        state_view,
        rrb.TimeSeriesView(
            name="Carry (+ carrying, - empty)",
            origin=paths.CARRY,
            axis_y=rrb.ScalarAxis(range=(-1.0, 1.0)),
        ),
        column_shares=[3, 2, 2],
    )
    top = rrb.Horizontal(
        world_view(cam_names, eye),
        rrb.Grid(*cams, grid_columns=n_cols) if cams else rrb.Vertical(),
        column_shares=[1, 1],
    )
    return rrb.Blueprint(
        rrb.Vertical(top, bottom, row_shares=[3, 1]),
        rrb.TimePanel(timeline="time", state="collapsed"),
        collapse_panels=collapse_panels,
    )
