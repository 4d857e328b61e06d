"""python/examples/plot_paper.py draws its figure."""
import subprocess
import sys


def test_plot_paper_writes_a_png(root, tmp_path):
    out = tmp_path / "paper.png"
    subprocess.run([sys.executable, str(root / "python/examples/plot_paper.py"), "--out", str(out)],
                   check=True, cwd=tmp_path, timeout=300)
    assert out.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
