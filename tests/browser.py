"""Headless Chromium for tests that look at a page the way a person would.

``screenshot`` renders a file to a PNG; ``layout`` runs the page with a small
script and returns what the browser measured (element boxes, image sizes). Tests
call ``require_chromium`` first, which skips them when no browser is installed
(Debian: ``apt-get install -y chromium``).
"""

from __future__ import annotations

import html
import json
import shutil
import subprocess
import tempfile
from pathlib import Path

import pytest

WINDOW = (1400, 5600)  # CSS px; with the default device scale, screenshot px = CSS px
TIMEOUT_S = 120
_FLAGS = [
    "--headless",
    "--no-sandbox",
    "--disable-gpu",
    "--disable-quic",
    "--no-first-run",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
    "--hide-scrollbars",
    "--force-device-scale-factor=1",
]


def find_chromium() -> str | None:
    """Path of a Chromium binary, or None."""
    if Path("/usr/bin/chromium").exists():
        return "/usr/bin/chromium"
    return next(filter(None, map(shutil.which, ("chromium", "chromium-browser"))), None)


def require_chromium() -> str:
    """The Chromium binary, or skip the calling test with the reason."""
    binary = find_chromium()
    if binary is None:
        pytest.skip(
            "headless Chromium not found (/usr/bin/chromium or chromium on PATH); "
            "install the Debian package: apt-get install -y chromium"
        )
    return binary


def _run(args: list[str], page: Path, size: tuple[int, int]) -> str:
    with tempfile.TemporaryDirectory(prefix="chromium-profile-") as profile:
        done = subprocess.run(
            [
                require_chromium(),
                *_FLAGS,
                f"--user-data-dir={profile}",
                f"--window-size={size[0]},{size[1]}",
                *args,
                Path(page).resolve().as_uri(),
            ],
            capture_output=True,
            text=True,
            timeout=TIMEOUT_S,
            check=False,
        )
    assert done.returncode == 0, f"chromium failed ({done.returncode}): {done.stderr[-2000:]}"
    return done.stdout


# Software WebGL (SwiftShader) and time for the page's scripts, for MeshCat pages.
WEBGL_ARGS = (
    "--use-angle=swiftshader",
    "--enable-unsafe-swiftshader",
    "--virtual-time-budget=8000",
)


def screenshot(page: Path, png: Path, size: tuple[int, int] = WINDOW, extra=()) -> Path:
    """Render ``page`` in a window of ``size`` [CSS px] to ``png``; returns ``png``."""
    png = Path(png)
    png.unlink(missing_ok=True)
    _run([*extra, f"--screenshot={png}"], page, size)
    assert png.exists(), f"chromium wrote no screenshot for {page}"
    return png


_PROBE = """<script>
window.addEventListener("load", () => {
  const box = e => { const r = e.getBoundingClientRect();
    return {x: r.left + scrollX, y: r.top + scrollY, w: r.width, h: r.height}; };
  const out = {
    body: box(document.body), height: document.documentElement.scrollHeight,
    images: [...document.images].map(i => ({...box(i), complete: i.complete,
      natural: [i.naturalWidth, i.naturalHeight], alt: i.alt})),
    tables: [...document.querySelectorAll("table")].map(box),
    plots: [...document.querySelectorAll("div.plot")].map(e => ({...box(e), id: e.id,
      panels: e.querySelectorAll(".uplot").length})),
    canvases: [...document.querySelectorAll("canvas")].map(box),
    svgs: [...document.querySelectorAll("svg.view")].map(box),
  };
  const pre = document.createElement("pre");
  pre.id = "layout"; pre.textContent = JSON.stringify(out);
  document.body.appendChild(pre);
});
</script>"""


def layout(page: Path, size: tuple[int, int] = WINDOW) -> dict:
    """Boxes [CSS px, page coordinates] of the body, tables and images after load.

    Runs a copy of the page with a measuring script appended after all content,
    so the boxes above it are those of the page as shipped.
    """
    page = Path(page)
    probe = page.with_name(f".{page.stem}.probe.html")
    probe.write_text(page.read_text().replace("</body>", _PROBE + "</body>"))
    try:
        dom = _run(["--dump-dom", "--virtual-time-budget=5000"], probe, size)
    finally:
        probe.unlink(missing_ok=True)
    start = dom.index('<pre id="layout">') + len('<pre id="layout">')
    return json.loads(html.unescape(dom[start : dom.index("</pre>", start)]))


ARTIFACTS = Path(__file__).resolve().parent / "artifacts"


def keep_artifact(png: Path, name: str) -> Path:
    """Copy a screenshot to tests/artifacts/<name> (kept after the run; gitignored)."""
    ARTIFACTS.mkdir(exist_ok=True)
    target = ARTIFACTS / name
    shutil.copyfile(png, target)
    print(f"screenshot kept: {target}")
    return target
