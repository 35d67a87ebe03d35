"""Headless Chromium with the network off: what a page shows, read from the page itself.

Used by the report's browser test (``tests/test_report_browser.py``) and by the documentation's
screenshots (``python -m docsite.screenshots REPORT_DIR``), so the pictures in the docs are the
pages the test loaded. The network is off: every host name resolves to nothing and every
request goes to a proxy that is not there, so a page that needed the network shows it as a
failed resource in the probe.
"""
from __future__ import annotations

import html
import json
import re
import shutil
import subprocess
import tempfile
from pathlib import Path

CHROMIUM = shutil.which("chromium") or "/usr/bin/chromium"
FLAGS = ("--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
         "--disable-background-networking", "--disable-component-update", "--disable-sync",
         "--host-resolver-rules=MAP * ~NOTFOUND", "--proxy-server=http://127.0.0.1:9",
         "--hide-scrollbars")

#: Injected into a copy of the page: script errors and failed resources, then after load (and after
#: plotly's first figure answered a zoom and a legend click) what the page shows, into
#: <pre id="pk-probe"> for --dump-dom. ``SELECTORS`` names the elements to measure.
PROBE = """<script>
window.__pkErrors = [];
window.addEventListener('error', function (e) {
  window.__pkErrors.push('error: ' + (e.message || (e.target && (e.target.src || e.target.href)) || 'resource'));
}, true);
console.error = function () { window.__pkErrors.push('console.error: ' + Array.from(arguments).join(' ')); };
function __pkBox(sel) {
  var el = document.querySelector(sel);
  if (!el) return null;
  var r = el.getBoundingClientRect(), st = getComputedStyle(el);
  return {x: r.left + scrollX, y: r.top + scrollY, w: r.width, h: r.height, bg: st.backgroundColor,
          color: st.color, text: el.innerText.slice(0, 400)};
}
window.addEventListener('load', function () {
  var out = {boxes: {}, plots: [], height: document.documentElement.scrollHeight,
             width: document.documentElement.scrollWidth, client: document.documentElement.clientWidth};
  (window.__pkSelectors || []).forEach(function (s) { out.boxes[s] = __pkBox(s); });
  var gds = Array.from(document.querySelectorAll('.js-plotly-plot'));
  var done = function () {
    out.errors = window.__pkErrors;
    var pre = document.createElement('pre');
    pre.id = 'pk-probe';
    pre.textContent = JSON.stringify(out);
    document.body.appendChild(pre);
  };
  gds.forEach(function (gd) {
    out.plots.push({id: gd.id, traces: gd.data.length, svg: gd.querySelectorAll('.main-svg').length,
                    points: gd.querySelectorAll('.scatterlayer .trace').length});
  });
  if (!gds.length || !window.Plotly) { out.plotly = !!window.Plotly; done(); return; }
  var gd = gds[0], before = gd.layout.xaxis.range.slice();
  var mid = (before[0] + before[1]) / 2, span = (before[1] - before[0]) / 8;
  out.plotly = true;
  Plotly.relayout(gd, {'xaxis.range': [mid - span, mid + span]}).then(function () {
    out.zoom = {before: before, after: gd.layout.xaxis.range.slice()};
    return Plotly.restyle(gd, {visible: 'legendonly'}, [0]);
  }).then(function () {
    out.hidden = gd.data[0].visible;
    return Plotly.relayout(gd, {'xaxis.autorange': true});
  }).then(function () { return Plotly.restyle(gd, {visible: true}, [0]); }).then(done, function (e) {
    window.__pkErrors.push('plotly: ' + e); done(); });
});
</script>"""


def run(*args, timeout: float = 180) -> subprocess.CompletedProcess:
    profile = tempfile.mkdtemp(prefix="pk-chromium-")
    try:
        return subprocess.run([CHROMIUM, *FLAGS, f"--user-data-dir={profile}", *args], capture_output=True,
                              text=True, timeout=timeout, stdin=subprocess.DEVNULL)
    finally:
        shutil.rmtree(profile, ignore_errors=True)


def probe(page: Path, selectors=(), width: int = 1400) -> dict:
    """What Chromium shows of ``page`` (a file) at ``width`` px: boxes of ``selectors`` (position,
    size, background and text colour, text), the plotly figures and whether the first zoomed and
    hid a trace, the page's size, script errors and failed resources, Chromium's console lines."""
    text = page.read_text()
    sel = f"<script>window.__pkSelectors = {json.dumps(list(selectors))};</script>"
    copy = page.with_name(f"_probe_{page.name}")
    copy.write_text(text.replace("<head>", "<head>" + sel + PROBE, 1))
    try:
        p = run("--enable-logging=stderr", "--v=0", f"--window-size={width},1000", "--virtual-time-budget=15000",
                "--dump-dom", copy.resolve().as_uri())
    finally:
        copy.unlink(missing_ok=True)
    m = re.search(r'<pre id="pk-probe">(.*?)</pre>', p.stdout, re.S)
    if not m:
        raise AssertionError(f"Chromium did not run the page's load handler: {p.stderr[-2000:]}")
    seen = json.loads(html.unescape(m.group(1)))
    seen["console"] = [ln for ln in p.stderr.splitlines() if "CONSOLE" in ln or "Uncaught" in ln]
    return seen


def screenshot(page: Path, png: Path, width: int, height: int, fragment: str = "") -> Path:
    """A screenshot of ``page`` at ``width`` x ``height`` px."""
    p = run(f"--window-size={width},{height}", "--virtual-time-budget=15000", f"--screenshot={png}",
            page.resolve().as_uri() + fragment)
    if p.returncode != 0 or not png.is_file():
        raise RuntimeError(f"Chromium took no screenshot of {page}: {p.stderr[-1000:]}")
    return png


def crop(png: Path, box: dict, out: Path, pad: int = 8, max_h: int | None = None) -> Path:
    """``out``: the part of ``png`` inside ``box`` (a probe's box), ``pad`` px around it."""
    from PIL import Image
    with Image.open(png) as im:
        x0, y0 = max(0, int(box["x"]) - pad), max(0, int(box["y"]) - pad)
        x1 = min(im.width, int(box["x"] + box["w"]) + pad)
        y1 = min(im.height, int(box["y"] + (min(box["h"], max_h) if max_h else box["h"])) + pad)
        im.crop((x0, y0, x1, y1)).save(out, optimize=True)
    return out
