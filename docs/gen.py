"""Tables of the docs site generated from the code, so they cannot drift: the
plugin's options and ini keys, its markers, the KPI registry, the CLI's help,
the import layers (from tests/project/test_architecture.py), a drone's stepping order
(``mission/steps.py``), the blueprints, the computers and the resource limits.

Used by the mkdocs hook (docs/hooks.py): a page line ``<!-- gen:NAME -->`` is
replaced by ``TABLES[NAME]()``. Also runnable: ``python docs/gen.py kpis``."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


def _md(header: list[str], rows: list[list[str]]) -> str:
    esc = [[str(c).replace("|", "\\|").replace("\n", " ") for c in r] for r in rows]
    lines = ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    lines += ["| " + " | ".join(r) + " |" for r in esc]
    return "\n".join(lines) + "\n"


def _parser():
    import warnings

    from _pytest.config.argparsing import Parser

    from pytest_flockai import plugin

    with warnings.catch_warnings():         # pytest's Parser is private: its own options table
        warnings.simplefilter("ignore")
        parser = Parser(processopt=None)
    plugin.pytest_addoption(parser)
    return parser


def options() -> str:
    """Every command-line option the plugin adds, with its ini key."""
    parser = _parser()
    inis = set(parser._inidict)
    rows = []
    for group in parser._groups:
        for opt in group.options:
            names = ", ".join(f"`{n}`" for n in opt.names())
            dest = opt.attrs().get("dest", "")
            meta = opt.attrs().get("metavar") or ""
            ini = f"`{dest}`" if dest in inis else "-"
            rows.append([f"{names} {meta}".strip(), ini, opt.attrs().get("help", "")])
    return _md(["option", "ini key", "what it does"], rows)


def markers() -> str:
    """The markers the plugin registers, as `pytest --markers` prints them."""
    out = subprocess.run([sys.executable, "-m", "pytest", "--markers", "-p", "no:cacheprovider",
                          "--rootdir", str(ROOT / "docs")], capture_output=True, text=True,
                         cwd=ROOT / "docs", check=True).stdout
    rows = []
    for line in out.splitlines():
        if line.startswith("@pytest.mark.flockai") or line.startswith("@pytest.mark.kpi"):
            sig, _, text = line.partition(": ")
            rows.append([f"`{sig.removeprefix('@pytest.mark.')}`", text])
    return _md(["marker", "what it does"], rows)


def kpis() -> str:
    """The KPI registry: name, unit, better direction, description."""
    from pytest_flockai import kpis as registry

    rows = []
    for name in registry.names():
        k = registry.get(name)
        rows.append([f"`{k.name}`", k.unit, k.better or "-", k.description])
    return _md(["KPI", "unit", "better", "what it measures"], rows)


def cli() -> str:
    """`flockai --help` and each subcommand's help."""
    def run(*args: str) -> str:
        return subprocess.run([sys.executable, "-m", "pytest_flockai", *args], capture_output=True,
                              text=True, cwd=ROOT).stdout
    top = run("--help")
    out = ["```text", top.rstrip(), "```"]
    subs = []
    for line in top.splitlines():
        s = line.strip()
        if s.startswith("{") and s.endswith("}"):
            subs = s.strip("{}").split(",")
            break
    for sub in subs:
        out += ["", f"### `flockai {sub}`", "", "```text", run(sub, "--help").rstrip(), "```"]
    return "\n".join(out) + "\n"


def layers() -> str:
    """The import layers (``pytest_flockai/_layers.py``, which the architecture test reads)."""
    from pytest_flockai._layers import LAYERS

    rows = [[str(i), " ".join(f"`{m}`" for m in sorted(layer))] for i, layer in enumerate(LAYERS)]
    return _md(["layer", "modules and packages (each imports only from its layer or below)"], rows)


def step_order() -> str:
    """The components of one drone in the order the loop steps them (STEP_ORDER)."""
    from pytest_flockai.mission.steps import STEP_ORDER

    rows = [[str(i), f"`{s.component}`" if " " not in s.component else s.component,
             f"`{s.module}`" if not s.module.startswith("`") else s.module, s.does, s.clock]
            for i, s in enumerate(STEP_ORDER, 1)]
    return _md(["#", "component", "module", "does", "when it is due"], rows)


def blueprints() -> str:
    """The built-in blueprints with their mass and battery."""
    import pytest_flockai as fa

    rows = []
    for name in fa.blueprints():
        d = fa.drone(name)
        rows.append([f"`{name}`", f"{d.airframe.mass_kg:g}", f"{d.battery.capacity_mah:g} mAh",
                     "yes" if getattr(d, "datasheet", None) else "no"])
    return _md(["blueprint", "mass kg", "battery", "datasheet-level"], rows)


def devices() -> str:
    """The computers tasks can run on."""
    from pytest_flockai.compute import DEVICES

    rows = [[f"`{d.name}`", f"{d.idle_w:g}", f"{d.active_w:g}", d.runtimes[0] if d.runtimes
             else "-", f"{d.macs_per_s / 1e9:g}", f"{d.overhead_s * 1e3:g}", d.source]
            for d in DEVICES.values()]
    return _md(["device", "idle W", "busy W", "default runtime", "MAC-count rule GMAC/s",
                "overhead ms", "source"], rows)


def computers() -> str:
    """The computers' datasheets: units and peaks, memory bandwidth, power, runtimes."""
    from pytest_flockai.compute.devices import DEVICES

    rows = []
    for d in DEVICES.values():
        units = "; ".join(
            f"{u.kind}{f' ({u.name})' if u.name else ''}: {u.cores} x {u.clock_ghz:g} GHz, "
            + ", ".join(f"{p} {v / 1e9:,.0f} GMAC/s" for p, v in u.peak) for u in d.units)
        rows.append([f"`{d.name}`", d.mode or "-", units, f"{d.bandwidth_gbs:g}",
                     f"{d.memory_mb:g}", f"{d.idle_w:g}", f"{d.active_w:g}",
                     ", ".join(d.deployments), d.source])
    return _md(["computer", "power mode", "units (peak multiply-accumulates)", "DRAM GB/s",
                "memory MB", "idle W", "busy W", "runtime/target (first: default)", "source"],
               rows)


def loco() -> str:
    """A board never tuned: leave-one-computer-out (stored by benchmarks/latency_tune.py)."""
    sys.path.insert(0, str(ROOT / "benchmarks"))
    from latency_validation import loco_lines

    from pytest_flockai.compute import predict, published

    rows, _ = published.load_rows()
    table = predict.efficiencies()
    lines = loco_lines(table, published.summary(rows, table))
    return "\n".join(lines[2:]) + "\n" if lines else "(not computed yet)\n"


def datasheet_fields() -> str:
    """The fields of a computer's datasheet (``compute.datasheets.SCHEMA``)."""
    from pytest_flockai.compute.datasheets import SCHEMA

    what = {"num": "number > 0", "num0": "number >= 0", "int": "whole number > 0",
            "int0": "whole number >= 0", "str": "text", "list": "list of runtime names"}
    rows = [[f"`[computers.NAME{'.' + sub if sub else ''}]`", f"`{k}`", what[v]]
            for sub, fields in SCHEMA.items() for k, v in fields.items()]
    rows.append(["`[computers.NAME]`", "`based_on`", "a profile's name (your own datasheets "
                 "only): start from its tables, field by field"])
    return _md(["table", "field", "value"], rows)


def latency_validation() -> str:
    """Predicted / published latency per half and computer (benchmarks/latency_validation.py)."""
    sys.path.insert(0, str(ROOT / "benchmarks"))
    from latency_validation import fresh_lines, table_lines, verdict_lines

    from pytest_flockai.compute import predict, published

    rows, skipped = published.load_rows()
    if not rows:
        return "(no published rows with network summaries yet)\n"
    table = predict.efficiencies()
    s = published.summary(rows, table)
    keep = [ln for ln in table_lines(s) if "| computer/runtime |" not in ln]
    fresh = fresh_lines(rows, table)
    return ("\n".join(keep) + f"\n\n{len(rows)} rows used, {len(skipped)} skipped.\n\n"
            + "\n".join(verdict_lines(s)) + "\n"
            + ("\n" + "\n".join(fresh) + "\n" if fresh else ""))


def limits() -> str:
    """The resource limits of `pytest_flockai.limits` and their values."""
    from pytest_flockai import limits as lim

    rows = [[f"`{k}`", f"{v:,}" if isinstance(v, int) else f"{v:g}"]
            for k, v in vars(lim).items() if k.isupper() and isinstance(v, (int, float))]
    return _md(["limit", "value"], rows)


TABLES = {"options": options, "markers": markers, "kpis": kpis, "cli": cli, "layers": layers,
          "step_order": step_order, "blueprints": blueprints, "devices": devices, "limits": limits,
          "computers": computers, "latency_validation": latency_validation,
          "datasheet_fields": datasheet_fields, "loco": loco}


def public_modules() -> dict:
    """The documented subpackages: each module of the package named in ``fa.__all__``,
    and in their ``__all__`` (once, under its first public name; ``fa.strategies.st``,
    hypothesis' own, is not ours)."""
    import types

    import pytest_flockai as fa

    found: dict = {}
    todo = [(n, getattr(fa, n)) for n in sorted(fa.__all__)]
    while todo:
        name, obj = todo.pop(0)
        if isinstance(obj, types.ModuleType) and obj.__name__.startswith("pytest_flockai") \
                and all(obj is not m for m in found.values()):
            found[name] = obj
            todo += [(f"{name}.{m}", getattr(obj, m)) for m in obj.__all__]
    return found


def api() -> str:
    """One section per documented subpackage, listing exactly its ``__all__`` (the names
    that are modules have their own section), rendered by mkdocstrings."""
    import types

    out = []
    for name, mod in public_modules().items():
        members = [m for m in mod.__all__ if not isinstance(getattr(mod, m), types.ModuleType)]
        out += [f"::: {mod.__name__}", "    options:", f'      heading: "fa.{name}"',
                "      show_root_full_path: false", f"      members: [{', '.join(members)}]", ""]
    return "\n".join(out)


#: the API reference's subpackage sections (their ``__all__``)
TABLES["api"] = api


if __name__ == "__main__":
    for name in sys.argv[1:] or list(TABLES):
        print(TABLES[name]())
