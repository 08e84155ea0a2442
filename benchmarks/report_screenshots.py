"""Screenshots of the report at 360, 500 and 1280 px for docs/report.md (Debian's chromium).

    python benchmarks/report_screenshots.py [REPORT_DIR] [--out docs]

Without REPORT_DIR it writes the paper preset's report into a scratch folder first. Headless
Chromium's window is at least 500 px wide, so the 360 px page is drawn in an <iframe> of
that width and cropped. Each page is cropped to its content and reduced to 256 colours.
"""

from __future__ import annotations

import argparse
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

WIDTHS = (360, 500, 1280)
FRAME = ('<!doctype html><html><body style="margin:0"><iframe src="report.html" '
         'width="{w}" height="{h}" style="border:0"></iframe></body></html>')  # fmt: skip


def shoot(report: Path, width: int, out: Path, height: int = 16000) -> Path:
    from PIL import Image

    browser = next(c for c in ("chromium", "chromium-browser", "google-chrome") if shutil.which(c))
    page = report / "report.html"
    if width < 500:
        page = report / f"_frame{width}.html"
        page.write_text(FRAME.format(w=width, h=height))
    with tempfile.TemporaryDirectory() as prof:
        raw = Path(prof) / "raw.png"
        subprocess.run([browser, "--headless", "--no-sandbox", "--disable-gpu",
                        "--hide-scrollbars", f"--user-data-dir={prof}/p",
                        f"--window-size={max(width, 500)},{height}",
                        "--virtual-time-budget=10000", f"--screenshot={raw}", page.as_uri()],
                       check=True, capture_output=True, timeout=300)  # fmt: skip
        im = Image.open(raw).convert("RGB").crop((0, 0, width, height))
    import numpy as np

    # crop to the content: the last row with anything darker than the white background
    dark = np.flatnonzero(np.asarray(im.convert("L")).min(axis=1) < 245)
    bottom = min(height, int(dark[-1]) + 24 if dark.size else height)
    im = im.crop((0, 0, width, bottom)).quantize(256)
    im.save(out, optimize=True)
    if page.name.startswith("_frame"):
        page.unlink()
    return out


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("report", nargs="?", type=Path)
    ap.add_argument("--out", type=Path, default=Path(__file__).resolve().parents[1] / "docs")
    a = ap.parse_args()
    report = a.report
    if report is None:
        report = Path(tempfile.mkdtemp()) / "report"
        subprocess.run([sys.executable, "-m", "mrclutch", "report", "--preset", "paper",
                        "--out", str(report), "--no-progress"], check=True)  # fmt: skip
    for w in WIDTHS:
        print(shoot(report, w, a.out / f"report-{w}px.png"))


if __name__ == "__main__":
    main()
