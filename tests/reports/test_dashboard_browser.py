"""The dashboard of an example-style suite (``docs/make_pictures.py``'s SUITE: flights,
a fleet, a sweep, an xfail test, a test that flies nothing, a skipped one) in a
real headless Chromium at 1280 px: no table wider than the page, every collected
test listed, the headline's colour matching pytest's exit status, no console
error. Run twice: green, then red after the computer is swapped."""

import importlib.util
import json
import re
import subprocess
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
spec = importlib.util.spec_from_file_location("make_pictures", ROOT / "docs" / "make_pictures.py")
make_pictures = importlib.util.module_from_spec(spec)
spec.loader.exec_module(make_pictures)

BROWSER = make_pictures.chromium()
pytestmark = pytest.mark.skipif(
    BROWSER is None, reason="no Chromium installed (apt-get install chromium); .ci/run installs it")

#: measured in the page after its own script ran: written into the DOM for --dump-dom
PROBE = """<script>
window.__errors = [];
window.addEventListener("error", e => window.__errors.push(String(e.message)));
</script>"""
MEASURE = """<script>
setTimeout(() => {
  const vw = document.documentElement.clientWidth;
  const wide = Array.from(document.querySelectorAll("table")).map(t => {
    const box = t.closest(".scroll") || t; const r = box.getBoundingClientRect();
    const first = t.tHead.rows[0].cells[0].getBoundingClientRect();
    return {id: t.id, right: r.right, table: t.getBoundingClientRect().width, first: first.right};
  });
  const out = {vw: vw, page: document.documentElement.scrollWidth, tables: wide,
    status: getComputedStyle(document.getElementById("status")).color,
    errors: window.__errors};
  const pre = document.createElement("pre"); pre.id = "measured";
  pre.textContent = JSON.stringify(out); document.body.appendChild(pre);
}, 50);
</script>"""


def measure(html: Path, tmp: Path, width: int = 1280) -> tuple[dict, str, str]:
    text = html.read_text()
    probe = tmp / f"probe-{html.name}"
    probe.write_text(text.replace("<head>", "<head>" + PROBE, 1).replace(
        "</body>", MEASURE + "</body>"))
    res = subprocess.run([BROWSER, "--headless=new", "--no-sandbox", "--disable-gpu",
                          "--disable-dev-shm-usage", f"--window-size={width},1000",
                          "--enable-logging=stderr", "--v=0", "--virtual-time-budget=2000",
                          "--dump-dom", probe.as_uri()], capture_output=True, text=True,
                         timeout=120)
    assert res.returncode == 0, res.stderr[-2000:]
    m = re.search(r'<pre id="measured">(.*?)</pre>', res.stdout, re.S)
    assert m, res.stdout[-2000:]
    return json.loads(m.group(1).replace("&quot;", '"')), res.stdout, res.stderr


def console_errors(stderr: str) -> list[str]:
    return [line for line in stderr.splitlines()
            if "CONSOLE" in line and re.search(r"Uncaught|Error", line)]


@pytest.mark.slow
@pytest.mark.browser
def test_the_example_suite_dashboard_at_1280_px(tmp_path):
    folder = tmp_path / "suite"
    rc_green, green = make_pictures.run_suite(folder)
    rc_red, red = make_pictures.run_suite(folder, "raspberry-pi-4",
                                          baseline=folder / "baseline.json")
    assert (rc_green, rc_red) == (0, 1)
    collected = subprocess.run(
        [make_pictures.sys.executable, "-m", "pytest", "--collect-only", "-q", "-p",
         "no:cacheprovider", "test_example_style.py"], cwd=folder, capture_output=True,
        text=True, env={**make_pictures.os.environ, "PYTHONPATH": str(ROOT)}).stdout
    nodeids = [line for line in collected.splitlines() if "::" in line]
    assert len(nodeids) == 9
    for html, rc in ((green, rc_green), (red, rc_red)):
        got, dom, stderr = measure(html, tmp_path)
        assert got["errors"] == [] and console_errors(stderr) == []
        assert got["page"] <= got["vw"]                     # nothing wider than the page
        for t in got["tables"]:                             # each table fits or scrolls in its box
            assert t["right"] <= got["vw"] + 0.5, t
            assert t["first"] <= got["vw"], t               # the verdict column is in view
        fits = {t["id"]: t["table"] <= got["vw"] for t in got["tables"]}
        assert all(fits[k] for k in ("tests", "broken", "budgets") if k in fits), fits
        tests_table = dom[dom.index('id="tests"'):dom.index("</table>", dom.index('id="tests"'))]
        ids = [re.sub("<wbr>", "", x) for x in re.findall(r'class="id">(.*?)</td>', tests_table)]
        assert sorted(ids) == sorted(nodeids)
        colour = {0: "rgb(23, 110, 47)", 1: "rgb(179, 38, 30)"}[rc]
        assert got["status"] == colour
    text = red.read_text()
    assert text.index("computer: jetson-nano-10w -&gt; raspberry-pi-4") < text.index(
        'id="regressions"')
    assert "robustness map: detector recall" in text and "sweep envelope: flight_time_s" in text
    png = tmp_path / "shot.png"
    make_pictures.screenshot(red.as_uri(), png, 1280, 1000)
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
