"""KPI budgets: ``">= 24 min"``, ``"<= 1.5 s"``, ``"< 25%"``, ``"== 0"``.

A budget is an operator, a number and an optional unit. ``parse(kpi, text)``
checks the KPI name against the registry (``kpis.py``), converts the number to
the KPI's SI unit and returns a ``Budget``; ``Budget.evaluate(actual)`` gives
``(passed, margin)`` with the margin positive when the value is inside the
budget (for ``==`` the margin is ``-|actual - limit|``, 0 when equal).

Grammar::

    budget   := op number [unit]
    op       := "<" | "<=" | ">" | ">=" | "=="
    unit     := s ms min h | J kJ MJ Wh kWh | mW W kW | mm cm m km
                | m/s km/h | B kB KB MB GB | %

A bare number is in the KPI's SI unit; ``%`` is only for fractions (unit
"1"): ``"25%"`` is 0.25. Custom KPIs named ``<probe>.<metric>`` may be used
before they are registered: then any unit is accepted and converted to the SI
unit of its own dimension (``"2 MB"`` -> 2000 kB); once registered, the
registry's unit is checked.

Every error is a ``ConfigError`` naming the KPI, the budget text and what is
allowed. This module imports nothing from pytest.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass

from . import kpis as _kpis
from .errors import ConfigError, close_matches

OPERATORS = ("<", "<=", ">", ">=", "==")

#: unit text -> (SI unit of the KPI registry, factor to SI)
UNITS: dict[str, tuple[str, float]] = {
    # time
    "s": ("s", 1.0), "ms": ("s", 1e-3), "min": ("s", 60.0), "h": ("s", 3600.0),
    # energy
    "J": ("J", 1.0), "kJ": ("J", 1e3), "MJ": ("J", 1e6), "Wh": ("J", 3600.0),
    "mWh": ("J", 3.6), "kWh": ("J", 3.6e6),
    # power
    "W": ("W", 1.0), "mW": ("W", 1e-3), "kW": ("W", 1e3),
    # length
    "m": ("m", 1.0), "mm": ("m", 1e-3), "cm": ("m", 1e-2), "km": ("m", 1e3),
    # speed
    "m/s": ("m/s", 1.0), "km/h": ("m/s", 1.0 / 3.6),
    # data (the registry counts kilobytes, 1 kB = 1000 bytes)
    "B": ("kB", 1e-3), "kB": ("kB", 1.0), "KB": ("kB", 1.0), "MB": ("kB", 1e3), "GB": ("kB", 1e6),
    # fractions
    "%": ("fraction", 0.01),
}

_DIMENSION_UNITS = {dim: [u for u, (d, _) in UNITS.items() if d == dim]
                    for dim in {d for d, _ in UNITS.values()}}

_NUMBER = r"[+-]?(?:\d+(?:\.\d*)?|\.\d+)(?:[eE][+-]?\d+)?"
_RE = re.compile(rf"^\s*(?P<op>[^\d\s.+-]*)\s*(?P<num>{_NUMBER})\s*(?P<unit>\S*?)\s*$")


def _allowed_units(dim: str) -> str:
    units = _DIMENSION_UNITS.get(dim, [])
    if dim == "1":
        return "a bare number or %"
    if dim == "fraction":
        return "a bare number (0 to 1) or %"
    if dim == "count":
        return "a bare number (a count)"
    return ", ".join(units) + " or a bare number (" + dim + ")"


@dataclass(frozen=True)
class Budget:
    """A parsed budget: ``kpi op limit`` with ``limit`` in the KPI's SI unit.

    ``unit`` and ``factor`` remember how the budget was written, so values can
    be shown the same way (``format(value)``).
    """

    kpi: str
    op: str
    limit: float
    text: str
    unit: str = ""        # the unit as written ("" for a bare number)
    factor: float = 1.0   # SI value = written value * factor
    dimension: str = "1"  # SI unit of the limit: "s", "J", "W", "m", "m/s", "kB" or "1"

    def evaluate(self, actual) -> tuple[bool, float]:
        """(passed, margin): margin > 0 inside the budget, in SI units.

        A missing (None) or NaN value never passes (margin NaN).
        """
        if actual is None:
            return False, math.nan
        a = float(actual)
        if math.isnan(a):
            return False, math.nan
        lim = self.limit
        if self.op in ("<", "<="):
            margin = lim - a
            passed = a < lim if self.op == "<" else a <= lim
        elif self.op in (">", ">="):
            margin = a - lim
            passed = a > lim if self.op == ">" else a >= lim
        else:  # ==
            passed = a == lim or math.isclose(a, lim, rel_tol=1e-9, abs_tol=1e-12)
            margin = 0.0 if passed else -abs(a - lim)
        if margin != margin:  # inf - inf
            margin = math.nan
        return bool(passed), float(margin)

    def format(self, value) -> str:
        """``value`` (SI) in the unit the budget was written in."""
        if value is None or (isinstance(value, float) and math.isnan(value)):
            return "n/a"
        v = float(value) / self.factor
        if self.unit == "%":
            return f"{v:.4g}%"
        return f"{v:.4g} {self.unit}".rstrip() if self.unit else f"{v:.6g}" + (
            f" {self.dimension}" if self.dimension not in ("1", "fraction", "count") else "")

    def __str__(self):
        return f"{self.kpi} {self.text.strip()}"


def kpi_unit(kpi: str) -> str | None:
    """The SI unit of a KPI, or None for an unregistered custom ``probe.metric``.

    Raises ConfigError for an unknown built-in style name (no dot)."""
    if not isinstance(kpi, str) or not kpi:
        raise ConfigError(f"KPI name {kpi!r} is not allowed; expected a KPI name from "
                          f"pytest_flockai.kpis or '<probe>.<metric>'")
    k = _kpis.get(kpi)
    if k is not None:
        return k.unit
    if "." in kpi.strip(".") and " " not in kpi:
        return None
    raise ConfigError(f"unknown KPI {kpi!r}{close_matches(kpi, _kpis.names())}; allowed: a name "
                      f"from pytest_flockai.kpis.names() or a custom '<probe>.<metric>'")


def parse(kpi: str, text) -> Budget:
    """Parse one budget for one KPI; raises ConfigError naming KPI, text and what is allowed."""
    if isinstance(text, Budget):
        if text.kpi != kpi:
            return parse(kpi, text.text)
        return text
    dim = kpi_unit(kpi)
    if not isinstance(text, str):
        raise ConfigError(f"KPI {kpi}: budget {text!r} is not a string; write it like "
                          f"'<= 1.5 s', '>= 24 min', '< 25%' or '== 0'")
    where = f"KPI {kpi}: budget {text!r}"
    m = _RE.match(text)
    if m is None:
        raise ConfigError(f"{where} is not understood; expected '<op> <number> [unit]' with "
                          f"op one of {', '.join(OPERATORS)}, e.g. '<= 1.5 s'")
    op, num, unit = m.group("op"), m.group("num"), m.group("unit")
    if op not in OPERATORS:
        shown = repr(op) if op else "no operator"
        raise ConfigError(f"{where}: {shown} is not allowed; allowed operators: "
                          f"{', '.join(OPERATORS)}")
    value = float(num)
    if unit == "" or (dim is not None and unit == dim and unit != "1"):
        factor, udim = 1.0, dim
    elif unit in UNITS:
        udim, factor = UNITS[unit]
    else:
        allowed = _allowed_units(dim) if dim is not None else ", ".join(UNITS)
        raise ConfigError(f"{where}: unknown unit {unit!r}{close_matches(unit, UNITS)}; "
                          f"allowed for {kpi}: {allowed}")
    if dim is not None and udim != dim and not (dim == "1" and udim == "fraction"):
        raise ConfigError(f"{where}: unit {unit!r} measures {_dim_name(udim)}, but {kpi} is in "
                          f"{dim!r} ({_dim_name(dim)}); allowed units: {_allowed_units(dim)}")
    limit = value * factor
    return Budget(kpi=kpi, op=op, limit=limit, text=text.strip(), unit=unit, factor=factor,
                  dimension=udim if udim is not None else "1")


def parse_many(budgets: dict) -> list[Budget]:
    """Parse ``{kpi: text}``; the first error is raised."""
    return [parse(k, v) for k, v in budgets.items()]


_DIM_NAMES = {"s": "time", "J": "energy", "W": "power", "m": "length", "m/s": "speed",
              "kB": "data size", "1": "a plain number", "fraction": "a fraction",
              "count": "a count"}


def _dim_name(dim) -> str:
    return _DIM_NAMES.get(dim, str(dim))


class BudgetError(AssertionError):
    """Raised by ``check`` when a budget is broken; the message is the budget table."""

    def __init__(self, message, verdicts):
        super().__init__(message)
        self.verdicts = verdicts


def evaluate(result, budgets: dict | None = None, **more) -> list[dict]:
    """Evaluate budgets against a FlightResult (or a KPI dict) without pytest.

    Returns one dict per budget: kpi, budget, limit, actual, passed, margin
    (positive inside the budget) and rel_margin (margin / |limit|).
    A budget on a KPI the flight did not produce raises ConfigError naming it.
    """
    kpis = getattr(result, "kpis", result)
    spec = dict(budgets or {})
    spec.update(more)
    out = []
    for b in parse_many(spec):
        if b.kpi not in kpis:
            raise ConfigError(f"budget on {b.kpi!r}: the flight did not produce this KPI; it has "
                              f"{', '.join(sorted(kpis))}")
        actual = kpis[b.kpi]
        passed, margin = b.evaluate(actual)
        scale = abs(b.limit) if b.limit else 1.0
        out.append({"kpi": b.kpi, "budget": b.text, "limit": b.limit, "actual": actual,
                    "passed": passed, "margin": margin, "rel_margin": margin / scale,
                    "actual_text": b.format(actual), "margin_text": b.format(margin)})
    return out


def check(result, budgets: dict | None = None, **more) -> list[dict]:
    """Like ``evaluate`` but raises BudgetError (an AssertionError) with a table
    when a budget is broken: use it inside hypothesis ``@given`` tests, where
    the failing example is then shrunk and shown."""
    verdicts = evaluate(result, budgets, **more)
    broken = [v for v in verdicts if not v["passed"]]
    if broken:
        width = max(len(v["kpi"]) for v in verdicts)
        lines = [f"{len(broken)} of {len(verdicts)} KPI budget(s) broken:"]
        for v in verdicts:
            lines.append(f"  {v['kpi']:<{width}}  {v['budget']:<12}  actual {v['actual_text']:<14} "
                         f"margin {v['margin_text']:<14} {'ok' if v['passed'] else 'BROKEN'}")
        raise BudgetError("\n".join(lines), verdicts)
    return verdicts


__all__ = ["Budget", "BudgetError", "OPERATORS", "UNITS", "check", "evaluate", "kpi_unit", "parse",
           "parse_many"]
