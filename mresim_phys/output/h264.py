"""H.264 video (output edge): frames piped to the ffmpeg that imageio-ffmpeg ships.

opencv-python-headless has no H.264 encoder, and the mp4v it has does not play in
browsers. :class:`FfmpegWriter` gives :class:`~mresim_phys.output.video.VideoRecorder` the
writer interface it uses (``isOpened``, ``write``, ``release``) over ``libx264`` at
``yuv420p`` with the index at the front of the file (``+faststart``), which Chromium,
Firefox and Safari play as soon as the first bytes arrive. ffmpeg encodes in its own
process, so the simulation's process only pipes raw BGR frames.
"""

from __future__ import annotations

from collections.abc import Generator
from pathlib import Path
from typing import Any

import numpy as np

from mresim_phys.errors import MresimError

CRF = 23  # x264's default quality (lower: better, larger)
OUTPUT = ["-pix_fmt", "yuv420p", "-movflags", "+faststart", "-crf", str(CRF), "-preset", "medium"]


class FfmpegWriter:
    """An H.264 MP4 of BGR frames of one size (module docstring)."""

    def __init__(self, path: Path, fps: float, frame_size: tuple[int, int]) -> None:
        try:
            import imageio_ffmpeg
        except ImportError:  # a base dependency: only a broken install lacks it
            raise MresimError(
                f"video {path}: H.264 needs imageio-ffmpeg (pip install imageio-ffmpeg), or"
                " give render.codec: mp4v"
            ) from None
        self.path = path
        self._pipe: Generator[Any, Any, None] | None = imageio_ffmpeg.write_frames(
            str(path), frame_size, fps=fps, codec="libx264", pix_fmt_in="bgr24",
            output_params=OUTPUT, macro_block_size=2, ffmpeg_log_level="error",
            ffmpeg_timeout=0,
        )  # fmt: skip
        try:
            self._pipe.send(None)  # starts ffmpeg
        except (OSError, RuntimeError) as exc:
            self._pipe = None
            self.error = str(exc)
        else:
            self.error = ""

    def isOpened(self) -> bool:
        """Whether ffmpeg started."""
        return self._pipe is not None

    def write(self, frame: np.ndarray) -> None:
        """Pipe one frame; MresimError if ffmpeg has stopped."""
        if self._pipe is None:
            raise MresimError(f"video {self.path}: ffmpeg is not running ({self.error})")
        try:
            self._pipe.send(np.ascontiguousarray(frame))
        except (OSError, RuntimeError) as exc:
            raise MresimError(f"video {self.path}: ffmpeg stopped: {exc}") from None

    def release(self) -> None:
        """Close the pipe and wait for ffmpeg to finish the file."""
        pipe, self._pipe = self._pipe, None
        if pipe is not None:
            try:
                pipe.close()
            except (OSError, RuntimeError) as exc:
                raise MresimError(f"video {self.path}: ffmpeg failed: {exc}") from None
