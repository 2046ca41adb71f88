"""examples/python/plot_run.py: runs a scene and writes a PNG with the three panels."""

import subprocess
import sys

import numpy as np
from matplotlib import image

from conftest import PROBE_S


def test_plot_run_writes_a_picture_of_the_run(source_dir, tmp_path):
    out = tmp_path / "run.png"
    r = subprocess.run([sys.executable, str(source_dir / "examples" / "python" / "plot_run.py"),
                        "probe", "--duration", str(PROBE_S), "--out", str(out)],
                       capture_output=True, text=True)
    assert r.returncode == 0, r.stdout + r.stderr
    assert out.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    img = image.imread(out)
    assert img.shape[:2] == (900, 900)  # figsize 9 x 9 in at 100 dpi
    rgb = (img[..., :3] * 255).round().astype(np.uint8).reshape(-1, 3)
    colours = {tuple(c) for c in rgb}
    # Lines, text and antialiasing: many colours, among them matplotlib's first two line colours
    # (C0 blue, C1 orange), each on at least a few hundred pixels.
    assert len(colours) > 100
    for c in ((0x1F, 0x77, 0xB4), (0xFF, 0x7F, 0x0E)):
        assert (rgb == c).all(axis=1).sum() > 300, c
    assert "probe: 2000 ticks" in r.stdout
