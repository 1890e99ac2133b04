"""Open the HTML report in headless Chromium and fail on what a reader would see broken: a
JavaScript error, an image that does not load, a 3-D view that does not draw. Also saves a
screenshot of the page's top.

    scripts/install_chromium.sh            # Debian's chromium, once
    python scripts/check_report.py [outputs/report] [--screenshot docs/figures/report.png [--view N]]

Every view is drawn in turn (as its button would), within Chromium's virtual time; the result
is read back from the page. Exit status 0 when all is well, 1 otherwise (with what failed).
"""

from __future__ import annotations

import argparse
import json
import re
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

# Before the page's own scripts: collect errors. After load: check images, draw every view.
PROBE = """<script>
window.__errors = [];
window.addEventListener('error', e => window.__errors.push(String(e.message || e.type)), true);
const __consoleError = console.error;
console.error = (...a) => { window.__errors.push(a.map(String).join(' ')); __consoleError(...a); };
window.addEventListener('load', async () => {
  const broken = [...document.images].filter(i => !i.complete || i.naturalWidth === 0)
    .map(i => i.getAttribute('src'));
  const views = [...document.querySelectorAll('figure.view')];
  let drawn = 0;
  for (const view of views) {
    try {
      await draw(view);
      if (view.querySelector('.plot canvas') && view.querySelector('.plot .main-svg')) drawn++;
    } catch (e) { window.__errors.push('view ' + view.id + ': ' + e); }
  }
  document.body.setAttribute('data-check', JSON.stringify(
    {images: document.images.length, broken, views: views.length, drawn, errors: window.__errors}));
});
</script>"""
FLAGS = ["--headless", "--no-sandbox", "--disable-gpu", "--use-angle=swiftshader",
         "--enable-unsafe-swiftshader", "--disable-background-networking",
         "--disable-component-update", "--disable-sync", "--no-first-run", "--disable-quic"]


def chromium() -> str:
    for name in ("chromium", "chromium-browser", "google-chrome"):
        if shutil.which(name):
            return shutil.which(name)
    raise SystemExit("error: no Chromium on the PATH; run scripts/install_chromium.sh")


def check(report: Path, budget_ms: int = 600_000) -> dict:
    """The page's own account of itself after load: images, broken ones, views drawn, errors."""
    page = (report / "index.html").read_text()
    probe = report / ".check.html"  # beside the page, so its relative links resolve
    probe.write_text(page.replace("<head>", "<head>\n" + PROBE, 1))
    try:
        with tempfile.TemporaryDirectory() as profile:
            done = subprocess.run(
                [chromium(), *FLAGS, f"--user-data-dir={profile}", f"--virtual-time-budget={budget_ms}",
                 "--dump-dom", probe.resolve().as_uri()],
                capture_output=True, text=True, timeout=900)
    finally:
        probe.unlink(missing_ok=True)
    found = re.search(r'data-check="([^"]*)"', done.stdout)
    if not found:
        return {"errors": [f"the page did not finish loading (chromium exit {done.returncode}): "
                           f"{done.stderr.strip()[-500:]}"], "broken": [], "views": 0, "drawn": 0}
    return json.loads(found.group(1).replace("&quot;", '"').replace("&amp;", "&"))


def screenshot(report: Path, path: Path, view: int | None = None) -> None:
    """The page's top as PNG, or 3-D view number ``view`` alone, drawn."""
    path.parent.mkdir(parents=True, exist_ok=True)
    page = report / "index.html"
    if view is not None:  # the page's head and script with that one view, drawn on load
        text = page.read_text()
        figure = re.search(rf'<figure class="view" id="view-{view}">.*?</figure>', text, re.S)
        if figure is None:
            raise SystemExit(f"error: no 3-D view {view} in {page}")
        page = report / ".shot.html"
        page.write_text(text[:text.index("<body>") + len("<body>")] + figure.group(0)
                        + text[text.rindex("<script>"):text.rindex("</body>")]
                        + f"<script>window.addEventListener('load', () => draw("
                          f"document.getElementById('view-{view}')));</script></body></html>")
    try:
        with tempfile.TemporaryDirectory() as profile:
            subprocess.run([chromium(), *FLAGS, f"--user-data-dir={profile}", f"--screenshot={path.resolve()}",
                            "--window-size=1280,1100" if view is None else "--window-size=1280,620",
                            "--hide-scrollbars", "--virtual-time-budget=60000",
                            page.resolve().as_uri()],
                           capture_output=True, text=True, timeout=300, check=True)
    finally:
        if view is not None:
            page.unlink(missing_ok=True)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("report", type=Path, nargs="?", default=Path("outputs/report"))
    parser.add_argument("--screenshot", type=Path, default=None, help="save the page's top as PNG")
    parser.add_argument("--view", type=int, default=None, help="with --screenshot: draw 3-D view N and show it")
    args = parser.parse_args(argv)
    if not (args.report / "index.html").is_file():
        print(f"error: {args.report / 'index.html'}: no report (python -m pipeline.report)", file=sys.stderr)
        return 2
    found = check(args.report)
    print(f"{found.get('images', 0)} images ({len(found['broken'])} broken), "
          f"{found['drawn']} of {found['views']} 3-D views drawn, {len(found['errors'])} errors")
    for line in [*found["broken"], *found["errors"]]:
        print(f"  {line}")
    if args.screenshot:
        screenshot(args.report, args.screenshot, args.view)
        print(f"screenshot: {args.screenshot}")
    return 0 if not found["broken"] and not found["errors"] and found["drawn"] == found["views"] else 1


if __name__ == "__main__":
    raise SystemExit(main())
