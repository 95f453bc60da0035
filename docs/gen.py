"""Tables of the docs site generated from the code, so they cannot drift: the
plugin's options and ini keys, its markers, the KPI registry, the CLI's help,
the import layers (from tests/test_architecture.py), a drone's stepping order
(``mission/steps.py``), the blueprints, the computers and the resource limits.

Used by the mkdocs hook (docs/hooks.py): a page line ``<!-- gen:NAME -->`` is
replaced by ``TABLES[NAME]()``. Also runnable: ``python docs/gen.py kpis``."""

from __future__ import annotations

import ast
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
    """The import layers, read from tests/test_architecture.py's own list."""
    tree = ast.parse((ROOT / "tests" / "test_architecture.py").read_text())
    for node in tree.body:
        if isinstance(node, ast.Assign) and any(getattr(t, "id", "") == "LAYERS" for t in node.targets):
            layers_ = ast.literal_eval(node.value)
            break
    else:
        raise RuntimeError("tests/test_architecture.py has no LAYERS list")
    rows = [[str(i), " ".join(f"`{m}`" for m in sorted(layer))] for i, layer in enumerate(layers_)]
    return _md(["layer", "modules and packages (each imports only from its layer or below)"], rows)


def step_order() -> str:
    """The components of one drone in the order the loop steps them (STEP_ORDER)."""
    from pytest_flockai.mission.steps import STEP_ORDER

    rows = [[str(i), f"`{s.component}`" if " " not in s.component else s.component,
             f"`{s.module}`" if not s.module.startswith("`") else s.module, s.does, s.clock]
            for i, s in enumerate(STEP_ORDER, 1)]
    return _md(["#", "component", "module", "does", "when it is due"], rows)


def public_api() -> str:
    """The public modules of ``pytest_flockai.__all__`` and the names each makes public."""
    import types

    import pytest_flockai as fa

    rows = []
    for name in sorted(fa.__all__):
        mod = getattr(fa, name) if name != "__version__" else None
        if isinstance(mod, types.ModuleType):
            names = getattr(mod, "__all__", None)
            shown = ", ".join(f"`{n}`" for n in sorted(names)) if names is not None \
                else "its names without a leading underscore"
            rows.append([f"`fa.{name}`", shown])
    return _md(["module", "public names"], rows)


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
    from pytest_flockai.compute.devices import DEVICES

    rows = [[f"`{d.name}`", f"{d.idle_w:g}", f"{d.active_w:g}", f"{d.macs_per_s / 1e9:g}",
             f"{d.overhead_s * 1e3:g}", d.source] for d in DEVICES.values()]
    return _md(["device", "idle W", "active W", "GMAC/s", "overhead ms", "source"], rows)


def limits() -> str:
    """The resource limits of `pytest_flockai.limits` and their values."""
    from pytest_flockai import limits as lim

    rows = [[f"`{k}`", f"{v:,}" if isinstance(v, int) else f"{v:g}"]
            for k, v in vars(lim).items() if k.isupper() and isinstance(v, (int, float))]
    return _md(["limit", "value"], rows)


TABLES = {"options": options, "markers": markers, "kpis": kpis, "cli": cli, "layers": layers,
          "step_order": step_order, "public_api": public_api, "blueprints": blueprints, "devices": devices, "limits": limits}

if __name__ == "__main__":
    for name in sys.argv[1:] or list(TABLES):
        print(TABLES[name]())
