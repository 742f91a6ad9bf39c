"""`fatswarm plot RECORD OUT.mp4` pipes its frames to an ffmpeg process (a stand-in one here; the
rest of `fatswarm plot`'s video is tested in tests/unit/test_animate.py)."""

from __future__ import annotations

import argparse
import os
import pathlib
import subprocess
import sys

import pytest

from fatswarm.deploy.view.plot import add_arguments, main

pytestmark = pytest.mark.integration
SMALL = pathlib.Path(__file__).resolve().parents[1] / "data" / "replay-small.jsonl"  # 3 rounds


def run_plot(*argv: object) -> int:
    p = argparse.ArgumentParser()
    add_arguments(p)
    return main(p.parse_args([str(a) for a in argv]))


def test_an_mp4_goes_through_ffmpeg_frame_by_frame(
    tmp_path: pathlib.Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    """A stand-in ffmpeg on the PATH counts the raw frames matplotlib pipes to it."""
    pytest.importorskip("matplotlib")
    fake = tmp_path / "bin" / "ffmpeg"
    fake.parent.mkdir()
    fake.write_text(
        f"#!{sys.executable}\n"
        "import sys\n"
        "size = sys.argv[sys.argv.index('-s') + 1].split('x')\n"
        "data = sys.stdin.buffer.read()\n"
        "frame = int(size[0]) * int(size[1]) * 4\n"
        "open(sys.argv[-1], 'w').write(f'{len(data) // frame} {len(data) % frame}')\n"
    )
    fake.chmod(0o755)
    monkeypatch.setenv("PATH", f"{fake.parent}{os.pathsep}{os.environ['PATH']}")
    out = tmp_path / "run.mp4"
    assert run_plot(SMALL, out, "--fps", "4", "--speed", "3") == 0, capsys.readouterr().err
    assert out.read_text() == "5 0"  # 3 rounds at 3 per second, 4 fps: 4 frames and the first


def test_a_reader_that_goes_away_stops_the_progress_lines_not_the_video(
    tmp_path: pathlib.Path,
) -> None:
    """`fatswarm plot RECORD OUT.gif 2>&1 | head -2`: the GIF is written whole and the command
    exits 0 (it was 141 with no GIF); if the run ends before the pipe closes, the same holds."""
    pytest.importorskip("matplotlib")
    from PIL import Image

    out = tmp_path / "run.gif"
    argv = [sys.executable, "-P", "-m", "fatswarm", "plot", str(SMALL), str(out)]
    proc = subprocess.Popen(
        [*argv, "--fps", "10", "--speed", "1.5"], stdout=subprocess.PIPE, stderr=subprocess.STDOUT
    )
    try:
        assert proc.stdout is not None
        head = [proc.stdout.readline() for _ in range(2)]
        proc.stdout.close()  # as `head -2` does
        assert proc.wait(timeout=300) == 0, head
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
    assert head[0].startswith(b"fatswarm plot: writing 21 frames")
    with Image.open(out) as gif:
        assert getattr(gif, "n_frames", 1) == 21
