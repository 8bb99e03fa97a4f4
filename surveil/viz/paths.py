"""Rerun entity paths of the review recording: the only place they are spelt.

The tree mirrors the scene (world frame: metres, Z up)::

    world                         ViewCoordinates (static)
    world/floor                   floor grid (static)
    world/cameras/{cam}           Transform3D world_from_cam + Pinhole (static)
    world/cameras/{cam}/image     the video frame (EncodedImage, JPEG)
    world/cameras/{cam}/blobs     skin blob boxes (Boxes2D)
    world/cameras/{cam}/silhouettes   silhouette outlines (LineStrips2D)
    world/cameras/{cam}/targets   targets projected into the image (Points2D, labelled)
    world/candidates              3D candidate points (Points3D, faint)
    world/targets/{label}/estimate    a target's position (Points3D, labelled)
    world/targets/{label}/trail       its last ~1 s (LineStrips3D)
    world/targets/{label}/particles   its particles, when the tracker gives them
    world/targets/{label}/carried     the carried object, in its hue, beside the hand
    world/event                   the latest event's name, between its actors, for a moment
    events                        one TextLog per event, at its climax
    transitions                   tracker state changes (TextLog, DEBUG; not in the layout)
    states/{label}                tracker state lane (StateChange) or code (Scalars)
    carry/{label}                 carry per hand: +confidence carrying, -confidence empty

``{label}`` is the target label of formats.md (``p1/right_hand``, ``t7``): its slash makes the
person a parent entity, so a whole person can be shown or hidden at once.
"""

from __future__ import annotations

from surveil.datatypes import LABEL_RE

WORLD = "world"
FLOOR = "world/floor"
CAMERAS = "world/cameras"
CANDIDATES = "world/candidates"
TARGETS = "world/targets"
EVENTS = "events"
EVENT_MARKER = "world/event"
TRANSITIONS = "transitions"
STATES = "states"
CARRY = "carry"


def _label(label: str) -> str:
    if LABEL_RE.match(label) is None:
        raise ValueError(f"label must look like 'p1/head' or 't5', got {label!r}")
    return label


def camera_path(cam: str) -> str:
    """``world/cameras/{cam}``: the camera's transform and pinhole.

    >>> camera_path("cam0")
    'world/cameras/cam0'
    """
    return f"{CAMERAS}/{cam}"


def camera_image_path(cam: str) -> str:
    return f"{camera_path(cam)}/image"


def camera_blobs_path(cam: str) -> str:
    return f"{camera_path(cam)}/blobs"


def camera_silhouettes_path(cam: str) -> str:
    return f"{camera_path(cam)}/silhouettes"


def camera_targets_path(cam: str) -> str:
    return f"{camera_path(cam)}/targets"


def camera_overlay_paths(cam: str) -> tuple[str, ...]:
    """Everything drawn in the image plane of a camera (frame, blobs, outlines, targets)."""
    return (
        camera_image_path(cam),
        camera_blobs_path(cam),
        camera_silhouettes_path(cam),
        camera_targets_path(cam),
    )


def target_path(label: str) -> str:
    """``world/targets/{label}``: parent of everything drawn for one target.

    >>> target_path("p1/right_hand")
    'world/targets/p1/right_hand'
    """
    return f"{TARGETS}/{_label(label)}"


def target_estimate_path(label: str) -> str:
    return f"{target_path(label)}/estimate"


def target_trail_path(label: str) -> str:
    return f"{target_path(label)}/trail"


def target_particles_path(label: str) -> str:
    return f"{target_path(label)}/particles"


def target_carried_path(label: str) -> str:
    return f"{target_path(label)}/carried"


def state_path(label: str) -> str:
    """``states/{label}``: the tracker-state lane of a target.

    >>> state_path("t7")
    'states/t7'
    """
    return f"{STATES}/{_label(label)}"


def carry_path(label: str) -> str:
    """``carry/{label}``: carry of a hand, +confidence carrying, -confidence empty."""
    return f"{CARRY}/{_label(label)}"
