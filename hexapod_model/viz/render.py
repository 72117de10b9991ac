"""Scene output: meshcat's self-contained static HTML, and PNGs rendered by headless Chromium.

Several PNGs come from one Chromium launch: the HTML files are laid out as a column of
iframes on one page, Chromium (WebGL through SwiftShader, no display, no network) takes one
screenshot, and Pillow cuts it into tiles.
"""

from __future__ import annotations

import io
import shutil
import subprocess
import tempfile
from collections.abc import Sequence
from pathlib import Path

import numpy as np

from ..exceptions import RenderError
from ..extras import require
from ..files import atomic_write_bytes, atomic_write_text

CHROMIUM_NAMES = ("chromium", "chromium-browser", "google-chrome")
HIDE_CONTROLS = "<style>.dg{display:none!important}</style>"  # meshcat's control panel (dat.GUI)
MIN_SIZE = (1024, 768)


def check_size(size: tuple[int, int]) -> tuple[int, int]:
    """``size`` (width, height in pixels) of a PNG snapshot, or :class:`RenderError` when below :data:`MIN_SIZE`."""
    w, h = size
    if w < MIN_SIZE[0] or h < MIN_SIZE[1]:
        raise RenderError(f"snapshot size {w}x{h} is below the minimum {MIN_SIZE[0]}x{MIN_SIZE[1]}")
    return w, h


def find_chromium() -> str:
    """Path of a Chromium executable, or :class:`RenderError` saying what to install."""
    for name in CHROMIUM_NAMES:
        path = shutil.which(name)
        if path:
            return path
    raise RenderError(
        "PNG snapshots need headless Chromium: install the Debian package `chromium` "
        "(apt-get install chromium); the HTML snapshot works without it"
    )


def static_html(vis) -> str:
    """Meshcat's self-contained page of the scene (opens in a browser with no server), with the control panel hidden."""
    html = vis.static_html()
    return html.replace("</head>", HIDE_CONTROLS + "</head>", 1)


def write_html(vis, path: str | Path) -> Path:
    """Write :func:`static_html` to ``path`` atomically."""
    return atomic_write_text(path, static_html(vis))


def render_pngs(
    html_files: Sequence[str | Path],
    png_files: Sequence[str | Path],
    size: tuple[int, int] = (1280, 960),
    budget_ms: int = 8000,
) -> list[Path]:
    """Render each HTML file to the PNG of the same index, in one Chromium launch.

    ``size`` (width, height) in pixels, at least 1024x768.
    """
    Image = require("PIL.Image", "view", "reading the rendered snapshots")

    if len(html_files) != len(png_files) or not html_files:
        raise RenderError(f"need as many PNG paths as HTML files, got {len(png_files)} and {len(html_files)}")
    w, h = check_size(size)
    chromium = find_chromium()
    with tempfile.TemporaryDirectory(prefix="hexapod_render_") as tmp_name:
        tmp = Path(tmp_name)
        frames = "".join(f'<iframe src="{Path(f).resolve().as_uri()}"></iframe>' for f in html_files)
        page = tmp / "grid.html"
        page.write_text(
            "<!DOCTYPE html><html><head><style>body{margin:0;overflow:hidden}"
            f"iframe{{display:block;border:0;width:{w}px;height:{h}px}}</style></head>"
            f"<body>{frames}</body></html>"
        )
        shot = tmp / "grid.png"
        cmd = [
            chromium,
            "--headless",
            "--no-sandbox",
            "--enable-unsafe-swiftshader",
            "--use-angle=swiftshader",
            "--disable-background-networking",
            "--disable-component-update",
            "--disable-sync",
            "--no-first-run",
            "--hide-scrollbars",
            "--allow-file-access-from-files",
            f"--user-data-dir={tmp / 'profile'}",
            f"--screenshot={shot}",
            f"--window-size={w},{h * len(html_files)}",
            f"--virtual-time-budget={budget_ms}",
            page.as_uri(),
        ]
        try:
            run = subprocess.run(cmd, capture_output=True, text=True, timeout=120)
        except subprocess.TimeoutExpired:
            raise RenderError(f"Chromium did not finish rendering within 120 s ({chromium})") from None
        if run.returncode != 0 or not shot.exists():
            tail = run.stderr.strip().splitlines()[-1:] or ["no output"]
            raise RenderError(f"Chromium failed (exit {run.returncode}): {tail[0]}")
        grid = Image.open(shot).convert("RGB")
        out = []
        for k, png in enumerate(png_files):
            buf = io.BytesIO()
            grid.crop((0, k * h, w, (k + 1) * h)).save(buf, format="PNG")
            out.append(atomic_write_bytes(png, buf.getvalue()))
        return out


def pixels(png: str | Path) -> np.ndarray:
    """(H, W, 3) uint8 pixels of a PNG (for checks and tests)."""
    Image = require("PIL.Image", "view", "reading the rendered snapshots")

    return np.asarray(Image.open(png).convert("RGB"))
