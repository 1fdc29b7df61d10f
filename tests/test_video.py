"""Views (phase 8), output edge: frames written to video and image files."""

from __future__ import annotations

import subprocess
from collections.abc import Iterator
from pathlib import Path

import cv2
import numpy as np
import pytest

from mresim_phys.errors import MresimError
from mresim_phys.output.video import FOURCC, VideoRecorder, default_video_path, write_png

WIDTH, HEIGHT = 64, 48


def frames(n: int) -> list[np.ndarray]:
    """``n`` distinct frames: a grey level that changes, with a moving white square."""
    out = []
    for i in range(n):
        frame = np.full((HEIGHT, WIDTH, 3), 20 * i % 256, dtype=np.uint8)
        frame[10:20, 2 * i : 2 * i + 10] = 255
        out.append(frame)
    return out


def read_back(path: Path) -> list[np.ndarray]:
    capture = cv2.VideoCapture(str(path))
    assert capture.isOpened()
    out = []
    while True:
        ok, frame = capture.read()
        if not ok:
            break
        out.append(frame)
    capture.release()
    return out


def record(path: Path, n: int) -> VideoRecorder:
    with VideoRecorder(path, 10.0, (WIDTH, HEIGHT)) as video:
        for frame in frames(n):
            video.write(frame)
    return video


@pytest.mark.parametrize("suffix", [".mp4", ".avi"])
def test_frames_round_trip(tmp_path: Path, suffix: str) -> None:
    video = record(tmp_path / f"x{suffix}", 12)
    assert video.frames_written == 12 and video.fourcc == FOURCC[suffix]
    back = read_back(tmp_path / f"x{suffix}")
    assert len(back) == 12
    assert all(f.shape == (HEIGHT, WIDTH, 3) for f in back)
    capture = cv2.VideoCapture(str(tmp_path / f"x{suffix}"))
    assert int(capture.get(cv2.CAP_PROP_FRAME_WIDTH)) == WIDTH
    assert int(capture.get(cv2.CAP_PROP_FRAME_HEIGHT)) == HEIGHT
    capture.release()
    # Lossy, but close: the last frame is mostly its grey level.
    assert abs(float(np.median(back[-1])) - 20 * 11 % 256) < 12


def test_webm_when_vp8_is_available(tmp_path: Path) -> None:
    try:
        video = record(tmp_path / "x.webm", 8)
    except MresimError as error:
        pytest.skip(f"VP80 writer not available here: {error}")
    assert video.frames_written == 8
    assert len(read_back(tmp_path / "x.webm")) == 8


def test_missing_folders_are_created(tmp_path: Path) -> None:
    record(tmp_path / "a" / "b" / "x.mp4", 3)
    assert (tmp_path / "a" / "b" / "x.mp4").stat().st_size > 0


def test_bad_extension_is_a_user_error(tmp_path: Path) -> None:
    with pytest.raises(MresimError, match=r"\.gif.*\.mp4"):
        VideoRecorder(tmp_path / "x.gif", 10, (WIDTH, HEIGHT))


def test_unwritable_path_is_a_user_error(tmp_path: Path) -> None:
    (tmp_path / "file").write_text("not a folder")
    with pytest.raises(MresimError, match="file"):
        VideoRecorder(tmp_path / "file" / "x.mp4", 10, (WIDTH, HEIGHT))
    (tmp_path / "folder.mp4").mkdir()
    with pytest.raises(MresimError, match=r"H\.264"):
        VideoRecorder(tmp_path / "folder.mp4", 10, (WIDTH, HEIGHT))


def test_missing_codec_names_the_alternatives(tmp_path: Path) -> None:
    with pytest.raises(MresimError, match=r"H\.264.*mp4v"):
        VideoRecorder(tmp_path / "x.mp4", 10, (WIDTH, HEIGHT), fourcc="ZZZZ")


def test_bad_frames_are_refused(tmp_path: Path) -> None:
    with VideoRecorder(tmp_path / "x.mp4", 10, (WIDTH, HEIGHT)) as video:
        with pytest.raises(ValueError, match="expected"):
            video.write(np.zeros((WIDTH, HEIGHT, 3), np.uint8))  # transposed
        with pytest.raises(ValueError, match="uint8"):
            video.write(np.zeros((HEIGHT, WIDTH, 3), np.float32))
        video.write(frames(1)[0])
    assert video.frames_written == 1
    video.close()  # idempotent
    with pytest.raises(ValueError, match="closed"):
        video.write(frames(1)[0])


def test_bad_settings(tmp_path: Path) -> None:
    with pytest.raises(MresimError, match="positive"):
        VideoRecorder(tmp_path / "x.mp4", 0, (WIDTH, HEIGHT))


def test_recorder_closes_on_error(tmp_path: Path) -> None:
    with pytest.raises(RuntimeError), VideoRecorder(tmp_path / "x.mp4", 10, (WIDTH, HEIGHT)) as v:
        v.write(frames(1)[0])
        raise RuntimeError
    assert len(read_back(tmp_path / "x.mp4")) == 1


def test_background_encoding_equals_foreground(tmp_path: Path) -> None:
    for background in (True, False):
        with VideoRecorder(
            tmp_path / f"{background}.mp4", 10, (WIDTH, HEIGHT), None, background
        ) as v:
            for frame in frames(9):
                v.write(frame)
    back, fore = read_back(tmp_path / "True.mp4"), read_back(tmp_path / "False.mp4")
    assert len(back) == len(fore) == 9
    assert all(np.array_equal(a, b) for a, b in zip(back, fore, strict=True))


def test_frames_can_be_reused_after_write(tmp_path: Path) -> None:
    buffer = np.empty((HEIGHT, WIDTH, 3), np.uint8)
    with VideoRecorder(tmp_path / "x.mp4", 10, (WIDTH, HEIGHT)) as video:
        for value in (250, 5, 250, 5):
            buffer[:] = value
            video.write(buffer)
            buffer[:] = 128  # after write: must not reach the file
    levels = np.array([250, 5, 128])  # 128 would mean a frame changed after write
    nearest = [int(np.argmin(abs(levels - np.median(f)))) for f in read_back(tmp_path / "x.mp4")]
    assert nearest == [0, 1, 0, 1]


class FailingWriter:
    """Stands in for cv2.VideoWriter: opens, then fails on every frame."""

    fourcc = staticmethod(cv2.VideoWriter.fourcc)

    def __init__(self, *args: object) -> None:
        self.released = False

    def isOpened(self) -> bool:
        return True

    def write(self, frame: np.ndarray) -> None:
        raise cv2.error("no space left on device")

    def release(self) -> None:
        self.released = True


def test_encoding_failures_surface_on_close(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setattr(cv2, "VideoWriter", FailingWriter)
    video = VideoRecorder(tmp_path / "x.mp4", 10, (WIDTH, HEIGHT), fourcc="mp4v")
    video.write(frames(1)[0])
    with pytest.raises(MresimError, match="encoding failed: no space"):
        video.close()
    video.close()  # idempotent, also after a failure


def test_write_png(tmp_path: Path) -> None:
    frame = frames(3)[2]
    write_png(tmp_path / "sub" / "f.png", frame)
    assert (cv2.imread(str(tmp_path / "sub" / "f.png")) == frame).all()
    (tmp_path / "file").write_text("x")
    with pytest.raises(MresimError):
        write_png(tmp_path / "file" / "f.png", frame)
    with pytest.raises(MresimError, match="cannot write"):
        write_png(tmp_path / "f.unknown", frame)


def test_default_video_path() -> None:
    assert default_video_path("quickstart", 7) == Path("videos/quickstart-seed7.mp4")


def test_an_mp4_is_h264_yuv420p_with_its_index_first(tmp_path: Path) -> None:
    """What browsers play: H.264, 4:2:0, the moov atom before the frames (faststart)."""
    import imageio_ffmpeg

    path = tmp_path / "x.mp4"
    with VideoRecorder(path, 10, (WIDTH, HEIGHT)) as video:
        for frame in frames(12):
            video.write(frame)
    assert len(read_back(path)) == 12
    capture = cv2.VideoCapture(str(path))
    fourcc = int(capture.get(cv2.CAP_PROP_FOURCC)).to_bytes(4, "little")
    capture.release()
    assert fourcc in (b"h264", b"avc1")
    data = path.read_bytes()
    assert 0 < data.find(b"moov") < data.find(b"mdat")
    probe = subprocess.run(
        [imageio_ffmpeg.get_ffmpeg_exe(), "-hide_banner", "-i", str(path)],
        capture_output=True, text=True, check=False,
    )  # fmt: skip
    assert "h264" in probe.stderr and "yuv420p" in probe.stderr


def test_an_ffmpeg_that_stops_fails_the_video_and_leaves_no_file(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    import imageio_ffmpeg

    def broken(*args: object, **kwargs: object) -> Iterator[None]:
        yield None  # started
        raise BrokenPipeError("ffmpeg exited")

    monkeypatch.setattr(imageio_ffmpeg, "write_frames", broken)
    video = VideoRecorder(tmp_path / "x.mp4", 10, (WIDTH, HEIGHT))
    video.write(frames(1)[0])
    with pytest.raises(MresimError, match="ffmpeg stopped"):
        video.close()
    assert list(tmp_path.iterdir()) == []
