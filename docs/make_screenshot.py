"""Make ``docs/screenshot.png``: the Scenario A replay page mid-run, in headless Chromium.

Runs ``bt-manip run trees/husky_carry_wall.xml --world worlds/tb3_house.yaml --record``, opens
the replay page, moves to the middle of the carry (the panel in the gripper, the tree beside
it) and saves the page as a PNG (a palette one if it would exceed 280 kB). Needs Chromium and
the playwright package (the test extras)::

    python docs/make_screenshot.py [--out docs/screenshot.png] [--at 0.5]
"""

from __future__ import annotations

import argparse
import shutil
import sys
import tempfile
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
VIEWPORT = {"width": 1200, "height": 700}
MAX_BYTES = 280_000
BROWSER_ARGS = ["--headless", "--no-sandbox", "--disable-gpu", "--use-gl=swiftshader",
                "--enable-unsafe-swiftshader", "--no-first-run"]


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", default=str(REPO / "docs" / "screenshot.png"))
    parser.add_argument("--at", type=float, default=0.5,
                        help="where in the carry to stop, 0 (its start) .. 1 (its end)")
    args = parser.parse_args()
    chromium = shutil.which("chromium") or shutil.which("chromium-browser")
    if chromium is None:
        print("no Chromium installed", file=sys.stderr)
        return 2
    from PIL import Image
    from playwright.sync_api import sync_playwright

    from bt_manip.cli import main as bt_manip
    from bt_manip.viz.replay_page import read_replay

    with tempfile.TemporaryDirectory() as tmp:
        replay = Path(tmp) / "husky.html"
        code = bt_manip(["run", str(REPO / "trees" / "husky_carry_wall.xml"), "--world",
                         str(REPO / "worlds" / "tb3_house.yaml"), "--quiet", "--record",
                         str(replay)])
        if code != 0:
            return code
        header, _ = read_replay(replay)
        names = [n["name"] for n in header["tree"]["nodes"]]
        carry = names.index("carry_to_goal")
        changes = [(t, c) for t, i, c, _ in header["tree"]["events"] if i == carry]
        start = next(t for t, c in changes if c == 1)
        end = next(t for t, c in changes if c == 2)
        at = start + args.at * (end - start)
        shot = Path(tmp) / "shot.png"
        with sync_playwright() as p:
            browser = p.chromium.launch(executable_path=chromium, args=BROWSER_ARGS)
            page = browser.new_page(viewport=VIEWPORT)
            page.goto(replay.as_uri())
            page.wait_for_function("window.btReplay !== undefined", timeout=60000)
            page.mouse.move(5, 5)
            page.evaluate(f"btReplay.seek({at})")
            page.wait_for_timeout(800)
            page.screenshot(path=str(shot))
            browser.close()
        image = Image.open(shot).convert("RGB")
        image.save(args.out, optimize=True)
        if Path(args.out).stat().st_size > MAX_BYTES:
            # a palette keeps it small; the status colours must still come through exactly
            image.quantize(colors=256, method=Image.Quantize.MAXCOVERAGE,
                           dither=Image.Dither.NONE).save(args.out, optimize=True)
    print(f"wrote {args.out} ({Path(args.out).stat().st_size / 1e3:.0f} kB), t = {at:.2f} s")
    return 0


if __name__ == "__main__":
    sys.exit(main())
