"""The ``flockai`` command on bad input: exit 2 (usage or input error) with one line
naming the file, never a traceback and never 1 (which means "regression"); outputs
never replace a device or land beside a folder; names escaped for the terminal."""

import json
import os
import stat
import subprocess
import sys

import pytest

import pytest_flockai as fa
from pytest_flockai import cli
from pytest_flockai.cache import FlightCache, caching
from pytest_flockai.cache.store import entries
from pytest_flockai.reports import history

GOOD = {"t.py::test_a": {"flight": {"endurance_s": 1000.0}}}


def baseline(path, tests=GOOD):
    path.write_text(json.dumps({"schema": "pytest-flockai-baseline/1", "tests": tests}))
    return path


def report(path, tests):
    path.write_text(json.dumps({"schema": "pytest-flockai/1", "tests": tests}))
    return path


def deep(n=100_000):
    return "[" * n + "]" * n


def exits_2(argv, capsys, *words):
    assert cli.main([str(a) for a in argv]) == 2
    err = capsys.readouterr().err
    assert "Traceback" not in err and len(err.strip().splitlines()) == 1, err
    for w in words:
        assert str(w) in err, err
    return err


# -- compare ------------------------------------------------------------------------------------
@pytest.mark.parametrize("bad", ["folder", "missing", "deep", "fifo", "nodeid-int", "list"])
def test_compare_a_bad_input_exits_2_naming_it(tmp_path, capsys, bad):
    p = tmp_path / "bad.json"
    if bad == "folder":
        p.mkdir()
    elif bad == "deep":
        p.write_text(deep())
    elif bad == "fifo":
        os.mkfifo(p)
    elif bad == "nodeid-int":
        report(p, [{"nodeid": 3, "flights": []}])
    elif bad == "list":
        p.write_text("[1, 2]")
    exits_2(["compare", baseline(tmp_path / "b.json"), p], capsys, "bad.json")


@pytest.mark.skipif(os.geteuid() != 0, reason="mknod needs root")
def test_compare_json_never_replaces_a_device(tmp_path, capsys):
    dev = tmp_path / "full"
    os.mknod(dev, 0o600 | stat.S_IFCHR, os.makedev(1, 7))
    b = baseline(tmp_path / "b.json")
    exits_2(["compare", b, b, "--json", dev], capsys, "full", "device")
    assert stat.S_ISCHR(dev.stat().st_mode)
    exits_2(["compare", b, b, "--json", tmp_path], capsys, "is a directory")
    exits_2(["compare", b, b, "--json", tmp_path / "no" / "d.json"], capsys, "does not exist")


def test_compare_escapes_control_characters_in_names(tmp_path, capsys):
    evil = "t.py::test_\x1b[2J\x1b]0;pwned\x07"
    b = baseline(tmp_path / "b.json", {evil: {"f": {"endurance_s": 1000.0}}})
    n = baseline(tmp_path / "n.json", {evil: {"f": {"endurance_s": 500.0}}})
    assert cli.main(["compare", str(b), str(n)]) == 1      # a regression: still 1
    out = capsys.readouterr().out
    assert "\x1b" not in out and "\x07" not in out and "\\x1b[2J" in out


# -- merge --------------------------------------------------------------------------------------
@pytest.mark.parametrize("tests", [[{"outcome": "passed"}], None, "x", 3, [3]])
def test_merge_a_malformed_report_exits_2(tmp_path, capsys, tests):
    p = report(tmp_path / "in.json", tests)
    exits_2(["merge", tmp_path / "o.json", p], capsys, "in.json", "nodeid")
    assert not (tmp_path / "o.json").exists()


@pytest.mark.skipif(os.geteuid() != 0, reason="mknod needs root")
def test_merge_never_replaces_a_device_or_a_folder(tmp_path, capsys):
    dev = tmp_path / "full"
    os.mknod(dev, 0o600 | stat.S_IFCHR, os.makedev(1, 7))
    p = report(tmp_path / "in.json", [{"nodeid": "t::a", "outcome": "passed", "flights": []}])
    exits_2(["merge", dev, p], capsys, "special file")
    assert stat.S_ISCHR(dev.stat().st_mode)
    exits_2(["merge", tmp_path, p], capsys, "is a directory")
    assert cli.main(["merge", str(tmp_path / "o.json"), str(p)]) == 0


# -- history ------------------------------------------------------------------------------------
def record(d, name, tests, **kw):
    doc = {"schema": history.SCHEMA, "created": f"2026-01-0{name}T00:00:00", "commit": "abc",
           "tests": tests, **kw}
    (d / f"{name}.json").write_text(json.dumps(doc) if isinstance(tests, (dict, list, str))
                                    or tests is None else doc)


@pytest.mark.parametrize("bad", [{"t": "x"}, [], "str", {"t": {"f": {"endurance_s": "1"}}},
                                 "commit-int", "deep"])
def test_history_skips_a_malformed_record_with_a_warning_naming_it(tmp_path, capsys, bad):
    record(tmp_path, "1", {"t::a": {"f": {"endurance_s": 10.0}}})
    if bad == "commit-int":
        record(tmp_path, "2", {"t::a": {"f": {"endurance_s": 11.0}}}, commit=7)
    elif bad == "deep":
        (tmp_path / "2.json").write_text(deep())
    else:
        record(tmp_path, "2", bad)
    assert cli.main(["history", str(tmp_path), "--kpi", "endurance_s"]) == 0
    cap = capsys.readouterr()
    assert "skipped" in cap.err and "2.json" in cap.err and "Traceback" not in cap.err
    assert "over 1 run(s)" in cap.out


@pytest.mark.skipif(os.geteuid() != 0, reason="mknod needs root")
def test_history_plot_into_a_folder_or_a_device_is_refused(tmp_path, capsys):
    record(tmp_path, "1", {"t::a": {"f": {"endurance_s": 10.0}}})
    dev = tmp_path / "full.png"
    os.mknod(dev, 0o600 | stat.S_IFCHR, os.makedev(1, 7))
    exits_2(["history", tmp_path, "--kpi", "endurance_s", "--plot", dev], capsys, "special")
    folder = tmp_path / "pics.png"
    folder.mkdir()
    exits_2(["history", tmp_path, "--kpi", "endurance_s", "--plot", folder], capsys, "directory")
    exits_2(["history", tmp_path, "--kpi", "endurance_s", "--plot", tmp_path / "t"], capsys,
            ".png")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["1.json", "full.png", "pics.png"]


def test_a_usage_error_exits_2_and_the_module_runs_without_traceback(tmp_path):
    out = subprocess.run([sys.executable, "-m", "pytest_flockai", "history", str(tmp_path / "x"),
                          "--kpi", "e"], capture_output=True, text=True)
    assert out.returncode == 2 and "does not exist" in out.stderr
    assert "Traceback" not in out.stderr
    out = subprocess.run([sys.executable, "-m", "pytest_flockai", "compare"],
                         capture_output=True, text=True)
    assert out.returncode == 2 and "Traceback" not in out.stderr


def test_a_reader_that_leaves_early_is_not_an_error():
    """``flockai blueprints | head -1``: the closed pipe is neither a message nor a failure."""
    p = subprocess.Popen([sys.executable, "-m", "pytest_flockai", "blueprints"],
                         stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    p.stdout.close()                        # before the command has printed anything
    err = p.stderr.read().decode()
    assert p.wait(timeout=60) == 0
    assert "BrokenPipe" not in err and "Exception ignored" not in err, err


# -- cache info / prune -------------------------------------------------------------------------
def test_cache_info_and_prune(tmp_path, capsys, monkeypatch):
    monkeypatch.setenv("FLOCKAI_CACHE_KEY", "k")
    with caching(FlightCache(tmp_path)):
        for seed in (0, 1):
            fa.Mission(fa.drone("crazyflie-2-1"), fa.pilots.Hover(1.0, 1.0), seed=seed).run()
    assert cli.main(["cache", "info", str(tmp_path)]) == 0
    out = capsys.readouterr().out
    assert "2 flight(s)" in out and "$FLOCKAI_CACHE_KEY" in out and "k\n" not in out
    size = max(p.stat().st_size for p in entries(tmp_path))
    assert cli.main(["cache", "prune", str(tmp_path), "--max-size", str(size + 10)]) == 0
    assert len(entries(tmp_path)) == 1 and "removed 1 entry" in capsys.readouterr().out
    assert cli.main(["cache", "prune", str(tmp_path), "--all"]) == 0
    assert entries(tmp_path) == []
    exits_2(["cache", "prune", tmp_path, "--max-size", "lots"], capsys, "--max-size", "lots")
    exits_2(["cache", "info", tmp_path / "none"], capsys, "does not exist")
