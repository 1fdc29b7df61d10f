"""Views (phase 8), output edge: rendered frames to video and image files.

:class:`VideoRecorder` streams frames to a ``cv2.VideoWriter`` as they come. By default
one background thread encodes them (OpenCV releases the GIL while it encodes), so on a
machine with a free core the simulation steps on while the last frame is encoded (an mp4v
800x600 frame costs ~2 ms of one core: the codec is single-threaded); at most
``QUEUED_FRAMES`` frames wait, then ``write`` blocks. The codec follows the file extension:
``.mp4`` -> ``mp4v``, ``.webm`` -> ``VP80``, ``.avi`` -> ``MJPG``. opencv-python-headless
ships no H.264 encoder; re-encode an mp4v file with an external ffmpeg if a browser needs
H.264. Frames go to a temporary sibling of the video file (``output.files``), renamed onto
its name at :meth:`VideoRecorder.close`, so a video file is always a finished one.
"""

from __future__ import annotations

import os
import queue
import threading
from pathlib import Path
from types import TracebackType

import cv2
import numpy as np

from mresim_phys.errors import MresimError
from mresim_phys.output.files import atomic_path, temp_sibling

FOURCC = {".mp4": "mp4v", ".webm": "VP80", ".avi": "MJPG"}
QUEUED_FRAMES = 4  # frames waiting for the background encoder (~1.4 MB each at 800x600)


def default_video_path(name: str, seed: int) -> Path:
    """Where a run's video goes unless the user says otherwise: ``videos/<name>-seed<seed>.mp4``."""
    return Path("videos") / f"{name}-seed{seed}.mp4"


def _make_parent(path: Path) -> None:
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise MresimError(f"cannot create the folder for {path}: {exc.strerror or exc}") from exc


def write_png(path: Path, frame: np.ndarray) -> None:
    """Write one frame as an image (format from the extension, normally ``.png``).

    Raises:
        MresimError: If the folder cannot be created or OpenCV cannot write the file.
    """
    path = Path(path)
    _make_parent(path)
    with atomic_path(path) as tmp:
        try:
            ok = cv2.imwrite(str(tmp), frame)
        except cv2.error as exc:
            raise MresimError(f"cannot write image {path}: {exc.msg or exc}") from exc
        if not ok:
            raise MresimError(f"cannot write image {path} (unwritable path or unknown extension)")


class VideoRecorder:
    """Write BGR uint8 frames of one size to a video file, one at a time.

    Use as a context manager; ``frames_written`` counts the frames accepted so far (all of
    them are in the file once :meth:`close` returns).
    """

    def __init__(
        self,
        path: Path,
        fps: float,
        frame_size: tuple[int, int],
        fourcc: str | None = None,
        background: bool = True,
    ) -> None:
        """Open the writer.

        Args:
            path: Output file; ``.mp4``, ``.webm`` or ``.avi``. Missing folders are created.
            fps: Frames per second of the video.
            frame_size: (width, height) of every frame.
            fourcc: Codec to use instead of the extension's default.
            background: Encode in a background thread (``write`` queues a copy of the frame).

        Raises:
            MresimError: On an unsupported extension or when the writer cannot be opened.
        """
        self.path, self.fps = Path(path), float(fps)
        self.frame_size = (int(frame_size[0]), int(frame_size[1]))
        self.frames_written = 0
        suffix = self.path.suffix.lower()
        if fourcc is None and suffix not in FOURCC:
            known = ", ".join(FOURCC)
            raise MresimError(f"video {self.path}: unsupported extension {suffix!r} (use {known})")
        if fps <= 0 or min(self.frame_size) <= 0:
            raise MresimError(f"video {self.path}: fps and frame size must be positive")
        self.fourcc = fourcc or FOURCC[suffix]
        _make_parent(self.path)
        self.partial = temp_sibling(self.path)  # renamed onto path by close()
        code = cv2.VideoWriter.fourcc(*self.fourcc)
        self._writer: cv2.VideoWriter | None = cv2.VideoWriter(
            str(self.partial), code, self.fps, self.frame_size
        )
        if not self._writer.isOpened() or self.path.is_dir():
            self._writer.release()
            self._writer = None
            self.partial.unlink(missing_ok=True)
            raise MresimError(
                f"cannot open video {self.path} with codec {self.fourcc!r}: the path may be "
                "unwritable, or the codec is missing from this OpenCV build (H.264 is not "
                "available in opencv-python-headless); use .mp4 (mp4v) or .webm (VP8)"
            )
        self._queue: queue.Queue[np.ndarray | None] | None = None
        self._encoder: threading.Thread | None = None
        self._failure: str | None = None
        if background:
            self._queue = queue.Queue(QUEUED_FRAMES)
            self._encoder = threading.Thread(
                target=self._encode, args=(self._writer, self._queue), daemon=True
            )
            self._encoder.start()

    def write(self, frame: np.ndarray) -> None:
        """Append one (height, width, 3) uint8 BGR frame.

        Raises:
            ValueError: If the frame has the wrong size or type, or the recorder is closed.
            MresimError: If encoding an earlier frame failed.
        """
        if self._writer is None:
            raise ValueError(f"video {self.path} is closed")
        width, height = self.frame_size
        if frame.dtype != np.uint8 or frame.shape != (height, width, 3):
            raise ValueError(
                f"frame {frame.shape} {frame.dtype} does not fit video {self.path}: "
                f"expected ({height}, {width}, 3) uint8"
            )
        self._raise_failure()
        if self._queue is None:
            self._writer.write(frame)
        else:
            self._queue.put(frame.copy())  # the caller may reuse its frame at once
        self.frames_written += 1

    def _encode(self, writer: cv2.VideoWriter, frames: queue.Queue[np.ndarray | None]) -> None:
        """The background thread: encode queued frames until the ``None`` sentinel."""
        while (frame := frames.get()) is not None:
            if self._failure is None:
                try:
                    writer.write(frame)
                except cv2.error as exc:  # reported by the next write or close
                    self._failure = exc.msg or str(exc)

    def _raise_failure(self) -> None:
        if self._failure is not None:
            raise MresimError(f"video {self.path}: encoding failed: {self._failure}")

    def close(self) -> None:
        """Encode the queued frames, finish the file and give it its name (idempotent).

        Raises:
            MresimError: If encoding a frame failed (the unfinished file is deleted).
        """
        writer, self._writer = self._writer, None
        if writer is None:
            return
        if self._queue is not None and self._encoder is not None:
            self._queue.put(None)
            self._encoder.join()
        writer.release()
        if self._failure is not None:
            self.partial.unlink(missing_ok=True)
            self._raise_failure()
        if self.partial.exists():
            os.replace(self.partial, self.path)

    def __enter__(self) -> VideoRecorder:
        return self

    def __exit__(
        self,
        exc_type: type[BaseException] | None,
        exc: BaseException | None,
        tb: TracebackType | None,
    ) -> None:
        self.close()
