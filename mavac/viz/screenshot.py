"""Screenshots of the exported HTML pages with headless Chromium (for tests and the README).

meshcat draws with WebGL; headless Chromium renders it on the CPU with SwiftShader. The page is
given a virtual-time budget so the scene (and the first frames of an animation) are drawn before
the screenshot is taken.
"""

from __future__ import annotations

import shutil
import subprocess
from pathlib import Path

#: executables tried, in order
BROWSERS = ("chromium", "chromium-browser", "google-chrome", "google-chrome-stable")


def find_chromium() -> str | None:
    """Path of a Chromium-family browser on PATH, or None."""
    for name in BROWSERS:
        path = shutil.which(name)
        if path:
            return path
    return None


def screenshot_html(html_path, png_path, size=(1280, 800), budget_ms: int = 15000,
                    timeout: float = 120.0) -> Path:
    """Render ``html_path`` headless and save a PNG.

    Raises
    ------
    ValueError
        No Chromium on PATH (install Debian's ``chromium``), a missing page, or a failed render.
    """
    browser = find_chromium()
    if browser is None:
        raise ValueError(f"no Chromium found (tried {', '.join(BROWSERS)}); install Debian's 'chromium'")
    html_path, png_path = Path(html_path).resolve(), Path(png_path).resolve()
    if not html_path.is_file():
        raise ValueError(f"html_path {str(html_path)!r} does not exist")
    png_path.parent.mkdir(parents=True, exist_ok=True)
    cmd = [browser, "--headless", "--no-sandbox", "--use-gl=swiftshader", "--enable-unsafe-swiftshader",
           "--hide-scrollbars", f"--window-size={size[0]},{size[1]}", f"--virtual-time-budget={budget_ms}",
           f"--screenshot={png_path}", html_path.as_uri()]
    done = subprocess.run(cmd, capture_output=True, text=True, timeout=timeout)
    if not png_path.is_file():
        raise ValueError(f"chromium wrote no screenshot (exit {done.returncode}): {done.stderr[-500:]}")
    return png_path
