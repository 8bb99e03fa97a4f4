"""Writing camera streams: a video file (or image folder) plus its timestamp CSV."""

from __future__ import annotations

from pathlib import Path

import cv2
import numpy as np

from surveil.errors import InputError


class FrameWriter:
    """Appends frames of one camera to ``<name>.mp4`` (MPEG-4 part 2, OpenCV's ``mp4v``) or to
    an image folder ``<name>/000000.jpg|png``, and their timestamps to ``<name>.csv``
    (header ``frame,timestamp_ns``, as formats.md says)."""

    def __init__(
        self,
        directory: Path,
        name: str,
        compression: str,
        fps: float,
        size: tuple[int, int],
        jpeg_quality: int = 85,
    ) -> None:
        self.directory = Path(directory)
        self.name = name
        self.compression = compression
        self.size = size
        self.jpeg_quality = jpeg_quality
        self.n = 0
        self._video: cv2.VideoWriter | None = None
        if compression == "mp4v":
            self.video_name = f"{name}.mp4"
            self._video = cv2.VideoWriter(
                str(self.directory / self.video_name), cv2.VideoWriter_fourcc(*"mp4v"), fps, size
            )
            if not self._video.isOpened():
                raise InputError(
                    f"{self.directory / self.video_name}: OpenCV cannot write "
                    f"mp4v video here; use effects.compression = 'jpeg'"
                )
        else:
            self.video_name = name
            (self.directory / name).mkdir(parents=True, exist_ok=True)
        self._csv = open(self.directory / f"{name}.csv", "w")
        self._csv.write("frame,timestamp_ns\n")

    def write(self, image: np.ndarray, timestamp_ns: int) -> None:
        if image.shape[1::-1] != self.size:
            raise ValueError(
                f"camera {self.name}: frame size {image.shape[1::-1]} differs from {self.size}"
            )
        if self._video is not None:
            self._video.write(image)
        elif self.compression == "jpeg":
            cv2.imwrite(
                str(self.directory / self.name / f"{self.n:06d}.jpg"),
                image,
                [cv2.IMWRITE_JPEG_QUALITY, self.jpeg_quality],
            )
        else:
            cv2.imwrite(str(self.directory / self.name / f"{self.n:06d}.png"), image)
        self._csv.write(f"{self.n},{int(timestamp_ns)}\n")
        self.n += 1

    def close(self) -> None:
        if self._video is not None:
            self._video.release()
            self._video = None
        if not self._csv.closed:
            self._csv.close()


def write_image(path: Path, image: np.ndarray) -> None:
    """Write a PNG/JPEG image, creating the folder; raise InputError if OpenCV cannot."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    if not cv2.imwrite(str(path), image):
        raise InputError(f"{path}: could not write image")
