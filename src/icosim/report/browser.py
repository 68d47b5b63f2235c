"""Check a built report in a real browser: headless Chromium (Debian's ``chromium`` package).

    python -m icosim.report.browser reports/icosim_report.html --screenshot results/report_screenshot.png

Chromium itself is the driver: ``--dump-dom`` prints the page after it has
loaded, ``--screenshot`` draws it.  No browser is downloaded and no driver
package is needed.

What is checked, and how:

* **Console errors.**  A copy of the page gets one small script at the top of
  its ``<head>`` that records, from the first moment, every JavaScript error,
  every resource that fails to load (``error`` events in the capture phase, the
  only way a broken ``<img>`` reports) and every ``console.error``; after the
  load event it writes what it found into a ``<pre id="__report_check">`` as
  JSON, which ``--dump-dom`` returns.  Independently, Chromium's own log
  (``--enable-logging=stderr``) is scanned for console lines -- that also
  catches what happens before the script runs (the report has no script, so
  any console message is a problem).
* **Images** are loaded (``complete``) with a non-zero natural size in the
  browser when the load event fires -- a broken image has size 0 -- and,
  independently, every ``data:`` image decodes fully with Pillow.  (The check
  runs synchronously in the load handler: ``--dump-dom`` prints the DOM right
  after the load event and waits for no promise.)
* **Internal links** (``href="#id"``) have a target ``id``, checked in the
  browser's DOM and in the HTML source; relative file links are listed with
  whether the file exists (datasets next to the report).
* **Load time**: the navigation timing of the page (``loadEventStart``: HTML
  parsed, every image loaded), and the
  page's size in bytes.  Measured, never asserted.
"""

from __future__ import annotations

import base64
import html.parser
import io
import json
import os
import shutil
import subprocess
import tempfile
import time
from pathlib import Path
from urllib.parse import unquote

__all__ = ["find_chromium", "check_report", "static_check", "screenshot", "CHROMIUM_FLAGS"]

#: Flags for a quiet, isolated headless run (no network, no first-run, no sync, no GPU).
CHROMIUM_FLAGS = (
    "--headless",
    "--no-sandbox",
    "--disable-gpu",
    "--disable-dev-shm-usage",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
    "--disable-extensions",
    "--no-first-run",
    "--no-default-browser-check",
    "--hide-scrollbars",
    "--mute-audio",
)

_CHECK_SCRIPT = """<script>(function(){
var errors=[];
window.addEventListener('error',function(e){var t=e.target;
 if(t&&t!==window&&(t.src||t.href)){errors.push('failed to load: '+String(t.src||t.href).slice(0,80));}
 else{errors.push('error: '+e.message);}},true);
window.addEventListener('unhandledrejection',function(e){errors.push('unhandled rejection: '+e.reason);});
var ce=console.error;console.error=function(){errors.push('console.error: '+Array.prototype.join.call(arguments,' '));
 return ce.apply(console,arguments);};
window.addEventListener('load',function(){
 var images=Array.prototype.slice.call(document.images).map(function(img){
   return {alt:img.alt,ok:img.complete&&img.naturalWidth>0&&img.naturalHeight>0,width:img.naturalWidth,height:img.naturalHeight};});
 var links=Array.prototype.slice.call(document.querySelectorAll('a[href^="#"]')).map(function(a){
   var id=decodeURIComponent(a.getAttribute('href').slice(1));return {href:a.getAttribute('href'),ok:!!document.getElementById(id)};});
 var nav=performance.getEntriesByType('navigation')[0];
 var out={errors:errors,images:images,links:links,
   load_ms:nav?nav.loadEventStart-nav.startTime:null,dom_content_loaded_ms:nav?nav.domContentLoadedEventEnd-nav.startTime:null};
 var pre=document.createElement('pre');pre.id='__report_check';pre.textContent=JSON.stringify(out);
 document.body.appendChild(pre);});
})();</script>"""


def find_chromium() -> str | None:
    """The Chromium executable on ``PATH`` (Debian: ``chromium``), or None."""
    for name in ("chromium", "chromium-browser", "google-chrome", "chrome"):
        path = shutil.which(name)
        if path:
            return path
    return None


def _run(chromium, args, *, timeout):
    with tempfile.TemporaryDirectory(prefix="icosim-chromium-") as profile:
        cmd = [chromium, *CHROMIUM_FLAGS, f"--user-data-dir={profile}", *args]
        return subprocess.run(cmd, capture_output=True, text=True, timeout=timeout, env={**os.environ, "LANG": "C"})


def _console_errors(stderr: str) -> list:
    """Chromium's log lines of console messages (``--enable-logging=stderr``).

    Chromium logs every console message at its INFO level (``INFO:CONSOLE(line)] "message"``),
    whatever the message's own level.  The report has no script of its own and the check script
    writes nothing to the console, so every such line is a problem (an uncaught error, a refused
    resource) and is returned.
    """
    return [line.strip() for line in stderr.splitlines() if ":CONSOLE" in line]


class _Parser(html.parser.HTMLParser):
    def __init__(self):
        super().__init__()
        self.ids, self.hrefs, self.images, self.check = set(), [], [], None
        self._in_check = False

    def handle_starttag(self, tag, attrs):
        a = dict(attrs)
        if "id" in a:
            self.ids.add(a["id"])
        if tag == "a" and "href" in a:
            self.hrefs.append(a["href"])
        if tag == "img":
            self.images.append((a.get("alt", ""), a.get("src", "")))
        self._in_check = tag == "pre" and a.get("id") == "__report_check"

    def handle_data(self, data):
        if self._in_check:
            self.check = (self.check or "") + data

    def handle_endtag(self, tag):
        if tag == "pre":
            self._in_check = False


def static_check(path) -> dict:
    """Checks from the HTML source alone: data images decode (Pillow), ``#`` links have targets,
    relative file links exist; the page's size."""
    from PIL import Image

    path = Path(path)
    p = _Parser()
    p.feed(path.read_text(encoding="utf-8"))
    images = []
    for alt, src in p.images:
        entry = {"alt": alt, "ok": False}
        if src.startswith("data:image/svg+xml;base64,"):
            text = base64.b64decode(src.split(",", 1)[1]).decode("utf-8", "replace")
            entry.update(ok="<svg" in text, kind="svg", bytes=len(text))
        elif src.startswith("data:image/"):
            raw = base64.b64decode(src.split(",", 1)[1])
            try:
                with Image.open(io.BytesIO(raw)) as im:
                    im.load()
                    entry.update(ok=im.width > 0 and im.height > 0, width=im.width, height=im.height)
            except OSError as exc:
                entry["error"] = str(exc)
            entry.update(kind=src[len("data:image/") : src.index(";")], bytes=len(raw))
        else:
            entry["error"] = f"not embedded: {src[:60]}"
        images.append(entry)
    internal = [{"href": h, "ok": unquote(h[1:]) in p.ids} for h in p.hrefs if h.startswith("#")]
    files = [
        {"href": h, "exists": (path.parent / unquote(h)).exists()}
        for h in p.hrefs
        if not h.startswith(("#", "http:", "https:", "mailto:", "data:"))
    ]
    return {"bytes": path.stat().st_size, "images": images, "links": internal, "file_links": files}


def screenshot(path, out, *, width=1280, height=1600, chromium=None, timeout=120) -> Path:
    """A PNG of the top of the page (``width`` x ``height`` CSS pixels)."""
    chromium = chromium or find_chromium()
    out = Path(out).resolve()
    out.parent.mkdir(parents=True, exist_ok=True)
    proc = _run(
        chromium,
        [f"--screenshot={out}", f"--window-size={width},{height}", Path(path).resolve().as_uri()],
        timeout=timeout,
    )
    if not out.exists() or out.stat().st_size == 0:
        raise RuntimeError(f"chromium wrote no screenshot (exit {proc.returncode}): {proc.stderr[-2000:]}")
    return out


def check_report(path, *, screenshot_path=None, chromium=None, timeout=180) -> dict:
    """Open the page in headless Chromium and check it (module docstring); returns what was found.

    Keys: ``errors`` (script-recorded and Chromium-logged console errors), ``images`` and ``links``
    (per element, ``ok``), ``load_ms`` (navigation timing), ``wall_s`` (the whole Chromium run),
    ``static`` (:func:`static_check`), ``screenshot`` (path, if asked for).
    """
    chromium = chromium or find_chromium()
    if chromium is None:
        raise FileNotFoundError("no Chromium on PATH (Debian: apt-get install chromium)")
    path = Path(path).resolve()
    text = path.read_text(encoding="utf-8")
    head = text.find("<head>")
    if head < 0:
        raise ValueError(f"{path}: no <head> to put the check script in")
    with tempfile.TemporaryDirectory(prefix="icosim-report-check-") as tmp:
        probe = Path(tmp) / path.name  # the page plus the recording script
        probe.write_text(text[: head + 6] + _CHECK_SCRIPT + text[head + 6 :], encoding="utf-8")
        t0 = time.perf_counter()
        proc = _run(
            chromium,
            ["--enable-logging=stderr", "--v=0", "--dump-dom", probe.as_uri()],
            timeout=timeout,
        )
        wall = time.perf_counter() - t0
    p = _Parser()
    p.feed(proc.stdout)
    if p.check is None:
        raise RuntimeError(
            f"the page's check did not report (chromium exit {proc.returncode}); stderr:\n{proc.stderr[-3000:]}"
        )
    found = json.loads(p.check)
    found["errors"] = found["errors"] + _console_errors(proc.stderr)
    found["wall_s"] = wall
    found["static"] = static_check(path)
    if screenshot_path is not None:
        found["screenshot"] = str(screenshot(path, screenshot_path, chromium=chromium, timeout=timeout))
    return found


def _main(argv=None) -> int:
    import argparse

    ap = argparse.ArgumentParser(prog="python -m icosim.report.browser", description=__doc__.split("\n\n")[0])
    ap.add_argument("report")
    ap.add_argument("--screenshot", help="PNG of the top of the page")
    args = ap.parse_args(argv)
    r = check_report(args.report, screenshot_path=args.screenshot)
    bad_images = [i for i in r["images"] if not i["ok"]]
    bad_links = [link["href"] for link in r["links"] if not link["ok"]]
    print(
        f"{args.report}: {r['static']['bytes'] / 1e6:.2f} MB, load {r['load_ms']:.0f} ms in headless Chromium; "
        f"{len(r['images'])} images ({len(bad_images)} not decoded), {len(r['links'])} internal links "
        f"({len(bad_links)} without target), {len(r['errors'])} console errors"
    )
    for e in r["errors"]:
        print("  error:", e)
    return 1 if bad_images or bad_links or r["errors"] else 0


if __name__ == "__main__":  # pragma: no cover
    raise SystemExit(_main())
