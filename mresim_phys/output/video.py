"""Views (phase 8), output edge: rendered frames to video and image files.

:class:`VideoRecorder` streams frames to a ``cv2.VideoWriter`` as they come. By default
one background thread encodes them (OpenCV releases the GIL while it encodes), so on a
machine with a free core the simulation steps on while the last frame is encoded (an mp4v
800x600 frame costs ~2 ms of one core: the codec is single-threaded); at most
``QUEUED_FRAMES`` frames wait, then ``write`` blocks. The codec follows the file extension,
or ``render.codec``: ``.mp4`` -> H.264 (``h264``: piped to the ffmpeg imageio-ffmpeg ships,
``output/h264.py``; browsers play it), or ``mp4v`` (OpenCV's, which browsers do not play),
``.webm`` -> VP8 (``vp8``), ``.avi`` -> ``mjpg``. Frames go to a temporary sibling of the
video file (``output.files``), renamed onto its name at :meth:`VideoRecorder.close`, so a
video file is always a finished one.

OpenCV's encoder reports no write errors (a full disk only logs a warning per frame and
leaves a file without its index), so :meth:`VideoRecorder.close` reads the finished file
back and counts its frames: a file without all of them is deleted and the failure raised
as a WriteError with its cause (:func:`~mresim_phys.output.files.probe_cause`). While a
recorder is open, OpenCV logs errors only (``quiet_opencv``), so a failing encoder does not
print a warning per frame.
"""

from __future__ import annotations

import queue
import threading
from pathlib import Path
from types import TracebackType
from typing import Any

import cv2
import numpy as np

from mresim_phys.errors import MresimError
from mresim_phys.output.files import (
    WriteError,
    atomic_path,
    commit_file,
    discard_file,
    make_parent,
    probe_cause,
    temp_sibling,
)
from mresim_phys.output.h264 import FfmpegWriter

FOURCC = {".mp4": "h264", ".webm": "VP80", ".avi": "MJPG"}  # the extension's default
CODECS = {"h264": "h264", "mp4v": "mp4v", "vp8": "VP80", "mjpg": "MJPG"}  # render.codec
H264 = "h264"  # not an OpenCV fourcc: output/h264.py's ffmpeg
QUEUED_FRAMES = 4  # frames waiting for the background encoder (~1.4 MB each at 800x600)


def default_video_path(name: str, seed: int) -> Path:
    """Where a run's video goes unless the user says otherwise: ``videos/<name>-seed<seed>.mp4``."""
    return Path("videos") / f"{name}-seed{seed}.mp4"


def chosen_video_path(value: str) -> Path:
    """A video path the user gave (``render.video``, ``--video``): its folder must exist.
    mresim creates only its own default folder, never one a path names (a typo such as
    ``/nonexistent_dir/x.mp4`` would make a folder at the top of the file system)."""
    path = Path(value).expanduser()
    if not path.parent.is_dir():
        raise MresimError(
            f"render.video (or --video): the folder {path.parent} of {value} does not exist or"
            " is not a folder. Create it first, or give a path in an existing folder."
        )
    return path


class _QuietOpenCV:
    """OpenCV logs errors only while any recorder is open; its level comes back after."""

    def __init__(self) -> None:
        self._lock = threading.Lock()
        self._users = 0
        self._level = 0

    def enter(self) -> None:
        with self._lock:
            if self._users == 0:
                self._level = cv2.utils.logging.getLogLevel()
                cv2.utils.logging.setLogLevel(cv2.utils.logging.LOG_LEVEL_ERROR)
            self._users += 1

    def leave(self) -> None:
        with self._lock:
            self._users -= 1
            if self._users == 0:
                cv2.utils.logging.setLogLevel(self._level)


quiet_opencv = _QuietOpenCV()


def write_png(path: Path, frame: np.ndarray) -> None:
    """Write one frame as an image (format from the extension, normally ``.png``).

    Raises:
        MresimError: If OpenCV knows no writer for the extension.
        WriteError: If the folder cannot be created or the file cannot be written.
    """
    path = Path(path)
    make_parent(path)
    with atomic_path(path) as tmp:
        try:
            ok = cv2.imwrite(str(tmp), frame)
        except cv2.error as exc:
            raise MresimError(f"cannot write image {path}: {exc.msg or exc}") from exc
        if not ok:
            cause = probe_cause(path.parent) or "OpenCV could not write it"
            raise WriteError(path, cause)


def frames_in(path: Path) -> int:
    """How many frames the video file ``path`` holds, as its index says (0: unreadable)."""
    capture = cv2.VideoCapture(str(path))
    try:
        return int(capture.get(cv2.CAP_PROP_FRAME_COUNT)) if capture.isOpened() else 0
    finally:
        capture.release()


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
        make_parent(self.path)
        self.partial = temp_sibling(self.path)  # renamed onto path by close()
        self._failure: str | None = None
        quiet_opencv.enter()
        try:
            self._writer: Any = self._open_writer()
        except BaseException:
            quiet_opencv.leave()
            raise
        if not self._writer.isOpened() or self.path.is_dir():
            self._release(self._writer)
            self._writer = None
            raise self._open_error()
        self._queue: queue.Queue[np.ndarray | None] | None = None
        self._encoder: threading.Thread | None = None
        if background:
            self._queue = queue.Queue(QUEUED_FRAMES)
            self._encoder = threading.Thread(
                target=self._encode, args=(self._writer, self._queue), daemon=True
            )
            self._encoder.start()

    def _open_writer(self) -> Any:
        """OpenCV's writer of the codec, or ffmpeg's for H.264."""
        if self.fourcc == H264:
            return FfmpegWriter(self.partial, self.fps, self.frame_size)
        code = cv2.VideoWriter.fourcc(*self.fourcc)
        return cv2.VideoWriter(str(self.partial), code, self.fps, self.frame_size)

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

    def _encode(self, writer: Any, frames: queue.Queue[np.ndarray | None]) -> None:
        """The background thread: encode queued frames until the ``None`` sentinel."""
        while (frame := frames.get()) is not None:
            if self._failure is None:
                try:
                    writer.write(frame)
                except cv2.error as exc:  # reported by the next write or close
                    self._failure = exc.msg or str(exc)
                except MresimError as exc:  # ffmpeg stopped
                    self._failure = str(exc)

    def _raise_failure(self) -> None:
        if self._failure is not None:
            raise MresimError(f"video {self.path}: encoding failed: {self._failure}")

    def _open_error(self) -> MresimError:
        """Why the writer did not open: a cause writing there shows, else the codec."""
        cause = None if self.path.is_dir() else probe_cause(self.path.parent)
        if cause is not None:
            return WriteError(self.path, cause)
        return MresimError(
            f"cannot open video {self.path} with codec {self.fourcc!r}: the path may be "
            "unwritable, or the codec is missing from this OpenCV build; use .mp4 (H.264, or"
            " codec mp4v) or .webm (VP8)"
        )

    def _release(self, writer: Any) -> None:
        """Release the writer (the file is then as complete as it gets)."""
        try:
            writer.release()
        except cv2.error as exc:  # reported by close
            self._failure = self._failure or exc.msg or str(exc)
        except MresimError as exc:  # ffmpeg failed
            self._failure = self._failure or str(exc)
        finally:
            quiet_opencv.leave()

    def _stop(self) -> bool:
        """Mark the recorder closed, let the encoder finish the queued frames and release
        the writer; False if the recorder was closed already."""
        writer, self._writer = self._writer, None
        if writer is None:
            return False
        if self._queue is not None and self._encoder is not None:
            self._queue.put(None)
            self._encoder.join()
        self._release(writer)
        return True

    def close(self) -> None:
        """Encode the queued frames, finish the file, check it holds every frame and give it
        its name (idempotent).

        Raises:
            MresimError: If encoding a frame failed (the unfinished file is deleted).
            WriteError: If the file lacks frames (a full disk, a file size limit: OpenCV
                reports nothing) or cannot be renamed; it is deleted.
        """
        if not self._stop():
            return
        if self._failure is not None:
            discard_file(self.partial)
            self._raise_failure()
        found = frames_in(self.partial) if self.frames_written else 0
        if found != self.frames_written:
            cause = probe_cause(self.path.parent)  # before deleting: that frees space
            discard_file(self.partial)
            written = f"{found} of the {self.frames_written} frames can be read back"
            raise WriteError(self.path, cause or f"the encoder failed silently ({written})")
        commit_file(self.partial, self.path)

    def discard(self) -> None:
        """Stop and delete the unfinished file: nothing appears under ``path`` (idempotent)."""
        if self._stop():
            discard_file(self.partial)

    def __enter__(self) -> VideoRecorder:
        return self

    def __exit__(
        self,
        exc_type: type[BaseException] | None,
        exc: BaseException | None,
        tb: TracebackType | None,
    ) -> None:
        self.close()
