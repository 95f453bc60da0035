"""The reports people look at (pytest_flockai/reports, harness/ci_reports.py): the
Markdown job summary, GITHUB_STEP_SUMMARY, and the HTML dashboard, this one
loaded in a real headless Chromium (skipped where none is installed)."""

import base64
import html.parser
import json
import re
import shutil
import subprocess

import pytest

from pytest_flockai.reports import html as dash
from pytest_flockai.reports import markdown

BODY = '''
import pytest
import pytest_flockai as fa


@pytest.mark.flockai(drone="crazyflie-2-1", pilot=fa.pilots.Hover(altitude=1.0, duration=2.0))
@pytest.mark.kpi(crashed="== 0", flight_time_s=">= 1 h")
def test_too_short(flight):
    pass


@pytest.mark.flockai(drone="crazyflie-2-1", pilot=fa.pilots.Hover(altitude=2.0, duration=3.0))
@pytest.mark.kpi(crashed="== 0")
def test_higher(flight, record_property, tmp_path):
    pic = tmp_path / "map.png"
    pic.write_bytes(PNG)
    record_property("flockai_picture", ("robustness map", str(pic)))
'''
# a 1x1 PNG, standing in for a robustness map a test attaches
PNG_BYTES = bytes.fromhex("89504e470d0a1a0a0000000d4948445200000001000000010806000000"
                          "1f15c4890000000d49444154789c6360f8cfc0f01f0005000201a5d6"
                          "6e9b0000000049454e44ae426082")


@pytest.fixture
def run_with_baseline(pytester):
    """Two tests; a baseline in which test_higher used less energy, so the run
    regresses on energy_total_j; -> (pytester, result, paths)."""
    pytester.makepyfile(test_flights=BODY.replace("PNG)", f"{PNG_BYTES!r})"))
    base = pytester.path / "base.json"
    pytester.runpytest_inprocess("-p", "no:cacheprovider", "--flockai-save", str(base))
    doc = json.loads(base.read_text())
    kp = doc["tests"]["test_flights.py::test_higher"]["flight"]
    kp["energy_total_j"] *= 0.8
    base.write_text(json.dumps(doc))
    paths = {k: pytester.path / f"out.{k}" for k in ("md", "html")}
    res = pytester.runpytest_inprocess("-p", "no:cacheprovider", "--flockai-baseline", str(base),
                                       "--flockai-md", str(paths["md"]),
                                       "--flockai-html", str(paths["html"]))
    return pytester, res, paths


def test_markdown_summary_and_github_step_summary(pytester, monkeypatch):
    step = pytester.path / "step_summary.md"
    step.write_text("# earlier step\n")
    monkeypatch.setenv("GITHUB_STEP_SUMMARY", str(step))
    pytester.makepyfile(test_flights=BODY.replace("PNG)", f"{PNG_BYTES!r})"))
    md = pytester.path / "summary.md"
    res = pytester.runpytest_inprocess("-p", "no:cacheprovider", "--flockai-md", str(md))
    res.assert_outcomes(passed=1, failed=1)
    res.stdout.fnmatch_lines(["flockai: Markdown summary written to *summary.md",
                              "flockai: job summary appended to GITHUB_STEP_SUMMARY"])
    text = md.read_text()
    assert "## pytest-flockai: ❌ 2 test(s) (1 passed, 1 failed), 2 flight(s)" in text
    assert "### Budgets broken (1)" in text
    assert "| test_flights.py::test_too_short | flight | flight_time_s | >= 1 h |" in text
    assert "No baseline given" in text
    rows = [line for line in text.splitlines() if line.startswith("| test_flights.py::")]
    assert len(rows) == 5                     # 1 broken budget + 2 tests + 2 KPI rows
    assert step.read_text() == "# earlier step\n" + text      # appended, not replaced


def test_markdown_lists_regressions(run_with_baseline):
    _, res, paths = run_with_baseline
    res.assert_outcomes(failed=2)
    text = paths["md"].read_text()
    assert "### Regressions against the baseline (1)" in text
    row = next(line for line in text.splitlines() if "| energy_total_j |" in line)
    assert row.startswith("| - | test_flights.py::test_higher | energy_total_j | 1 |")
    assert "+25.00%" in row and row.rstrip().endswith("| lower |")


def test_markdown_of_an_empty_run():
    text = markdown.job_summary({"summary": {"tests": 0, "flights": 0}, "tests": []})
    assert "✅ 0 test(s) (none run), 0 flight(s)" in text and "### KPIs (0 flight(s))" in text


class Tables(html.parser.HTMLParser):
    """Rows of each table by id (cell texts), and attributes of the tables."""

    def __init__(self):
        super().__init__()
        self.tables, self.attrs, self.images = {}, {}, []
        self._t = self._row = self._cell = None

    def handle_starttag(self, tag, attrs):
        a = dict(attrs)
        if tag == "table":
            self._t = a.get("id")
            self.tables[self._t], self.attrs[self._t] = [], a
        elif tag == "tr" and self._t:
            self._row = []
        elif tag in ("td", "th") and self._row is not None:
            self._cell = ""
        elif tag == "img":
            self.images.append(a)

    def handle_data(self, data):
        if self._cell is not None:
            self._cell += data

    def handle_endtag(self, tag):
        if tag in ("td", "th") and self._cell is not None:
            self._row.append(self._cell.strip())
            self._cell = None
        elif tag == "tr" and self._row is not None:
            self.tables[self._t].append(self._row)
            self._row = None
        elif tag == "table":
            self._t = None


def parse(text):
    p = Tables()
    p.feed(text)
    return p


def test_the_dashboard_is_one_self_contained_file(run_with_baseline):
    _, res, paths = run_with_baseline
    res.stdout.fnmatch_lines(["flockai: HTML dashboard written to *out.html"])
    text = paths["html"].read_text()
    assert "http://" not in text and "https://" not in text     # nothing fetched
    page = parse(text)
    budgets = page.tables["budgets"]
    assert budgets[0] == ["verdict", "test", "flight", "KPI", "budget", "actual", "margin", "from"]
    assert budgets[1][3] == "flight_time_s" and budgets[1][0] == "broken"   # broken first
    assert page.tables["broken"][1][:4] == budgets[1][:4]                    # and at the top
    deltas = {(r[1].split("::")[-1], r[3]): r for r in page.tables["deltas"][1:]}
    energy = deltas[("test_higher", "energy_total_j")]
    assert energy[0] == "regression" and energy[6] == "+25.00%"
    assert ("test_too_short", "energy_total_j") not in deltas        # unchanged: not listed
    (_head, reg), = [page.tables["regressions"]]
    assert reg[:2] == ["+25.00%", "energy_total_j"]
    kpis = page.tables["kpis"]
    assert kpis[0][:5] == ["outcome", "test", "flight", "source", "flight_time_s"]
    assert len(kpis) == 3
    assert [r[0] for r in page.tables["tests"][1:]] == ["failed", "failed"]
    titles = {i["alt"] for i in page.images}
    assert titles == {"flight: energy", "flight: flight path", "robustness map"}
    # 2 flights x (path, energy) + the map: each embedded, or linked when it looks the same
    assert len(page.images) + text.count("same picture as test_flights.py::") == 5
    assert all(i["src"].startswith("data:image/png;base64,") for i in page.images)


def _chromium():
    for name in ("chromium", "chromium-browser", "google-chrome", "chrome"):
        path = shutil.which(name)
        if path:
            return path
    return None


BROWSER = _chromium()
needs_browser = pytest.mark.skipif(
    BROWSER is None, reason="no Chromium installed (apt-get install chromium); the dashboard's "
                            "browser test runs where it is, as in .ci/run")


def _browser(*args, timeout=120):
    cmd = [BROWSER, "--headless=new", "--no-sandbox", "--disable-gpu", "--disable-dev-shm-usage",
           "--hide-scrollbars", *args]
    return subprocess.run(cmd, capture_output=True, text=True, timeout=timeout)


@needs_browser
@pytest.mark.slow
@pytest.mark.browser
def test_the_dashboard_in_a_headless_browser(run_with_baseline, tmp_path):
    """Chromium loads the page and runs its script: the tables are there, sorting by
    a KPI (through the page's own sort, asked for in the URL) orders the rows, and
    a screenshot of the page is taken."""
    _, _, paths = run_with_baseline
    url = paths["html"].resolve().as_uri()
    dom = _browser("--dump-dom", url + "#sort=kpis:energy_total_j:desc")
    assert dom.returncode == 0, dom.stderr[-2000:]
    page = parse(dom.stdout)
    assert {"budgets", "deltas", "kpis", "tests", "regressions"} <= set(page.tables)
    assert page.attrs["kpis"].get("data-sorted") == "energy_total_j:desc"
    col = page.tables["kpis"][0].index("energy_total_j")
    values = [float(r[col].split()[0]) for r in page.tables["kpis"][1:]]
    assert values == sorted(values, reverse=True) and values[0] > values[-1]
    dom_asc = _browser("--dump-dom", url + "#sort=kpis:energy_total_j:asc")
    rows_asc = parse(dom_asc.stdout).tables["kpis"][1:]
    assert [float(r[col].split()[0]) for r in rows_asc] == sorted(values)
    shot = tmp_path / "dashboard.png"
    res = _browser("--window-size=1280,1200", f"--screenshot={shot}", url)
    assert res.returncode == 0, res.stderr[-2000:]
    cv2 = pytest.importorskip("cv2")
    img = cv2.imread(str(shot))
    assert img is not None and img.shape[:2] == (1200, 1280)
    assert img.std() > 10                                   # not a blank page


def test_dashboard_without_flights_or_baseline():
    page = parse(dash.dashboard({"summary": {"tests": 0, "flights": 0}, "tests": []}))
    assert page.tables == {}
    text = dash.dashboard({"summary": {"tests": 0}, "tests": []})
    assert "No test has a kpi budget." in text and "No baseline given" in text
    assert 'id="status" class="ok"' in text            # no exit status, nothing failed




def test_pytest_html_extras(pytester):
    """With pytest-html, each test's row carries its KPI and budget tables and pictures."""
    pytest.importorskip("pytest_html")
    pytest.importorskip("matplotlib")
    pytester.makepyfile(test_flights=BODY.replace("PNG)", f"{PNG_BYTES!r})"))
    out = pytester.path / "report.html"
    res = pytester.runpytest_inprocess("-p", "no:cacheprovider", "--html", str(out),
                                       "--self-contained-html")
    res.assert_outcomes(passed=1, failed=1)
    text = out.read_text()
    assert text.count("flockai-kpis") == 2 and text.count("flockai-budgets") == 2
    assert "flight_time_s" in text
    assert re.search(r"(>|&gt;|&amp;gt;)= 1 h", text)             # the budget, however escaped
    # 2 flights x (path, energy) + the attached map; pytest-html escapes the extras' markup
    assert text.count("data:image/png;base64") >= 5


def test_a_picture_shared_by_several_tests_is_embedded_once():
    """A module-scoped flight's pictures appear under every test that uses it: the first
    embeds the image, the others link to it (the example suite's dashboard was 5.4 MB)."""
    shared = {"title": "hover: flight path", "data": base64.b64encode(PNG_BYTES).decode()}
    own = {"title": "map", "data": base64.b64encode(PNG_BYTES + b"x").decode()}
    doc = {"summary": {"tests": 3}, "tests": [{"nodeid": f"t.py::test_{i}"} for i in range(3)]}
    pics = {"t.py::test_0": [shared], "t.py::test_1": [shared, own], "t.py::test_2": [shared]}
    text = dash.dashboard(doc, pictures=pics)
    page = parse(text)
    assert sorted(i["alt"] for i in page.images) == ["hover: flight path", "map"]
    assert text.count(shared["data"]) == 1
    links = re.findall(r'<a href="#(pic-[0-9a-f]+)">same picture as t\.py::test_0</a>', text)
    assert len(links) == 2 and f'id="{links[0]}"' in text
    assert text.count("<figcaption") == 4                # every picture still has its caption
