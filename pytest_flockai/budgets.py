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
from collections.abc import Iterable, Mapping
from dataclasses import dataclass
from numbers import Real
from typing import TYPE_CHECKING

from . import kpis as _kpis
from .errors import ConfigError, close_matches
from .recording import publish_verdicts
from .reports.files import table as text_table

if TYPE_CHECKING:
    from .result import FlightResult

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
    # voltage
    "V": ("V", 1.0), "mV": ("V", 1e-3),
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

    def evaluate(self, actual: float | None) -> tuple[bool, float]:
        """(passed, margin): margin > 0 inside the budget, in SI units.

        A missing (None) or NaN value never passes (margin NaN).
        """
        if actual is None:
            return False, math.nan
        if isinstance(actual, (bool, str, bytes)) or not isinstance(actual, Real):
            raise ConfigError(f"KPI {self.kpi}: value {actual!r} is not a number; budgets are "
                              f"checked against numeric KPIs")
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

    def verdict(self, actual: float | None, flight: str | None = None) -> Verdict:
        """The one verdict type: this budget against ``actual`` (SI)."""
        passed, margin = self.evaluate(actual)
        a = math.nan if actual is None else float(actual)
        return Verdict(flight=flight, kpi=self.kpi, budget=self.text, op=self.op, limit=self.limit,
                       actual=a, margin=margin, passed=passed, actual_text=self.format(actual),
                       margin_text=self.format(margin) if margin == margin else "n/a")

    def format(self, value: float | None) -> str:
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


def parse(kpi: str, text: str | Budget) -> Budget:
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
    if not math.isfinite(limit):      # '<= 1e999 J' would never fail
        raise ConfigError(f"{where}: the limit {num} is not a finite number (it overflows to "
                          f"{limit}); allowed: a finite number")
    return Budget(kpi=kpi, op=op, limit=limit, text=text.strip(), unit=unit, factor=factor,
                  dimension=udim if udim is not None else "1")


@dataclass(frozen=True)
class Verdict:
    """A budget checked against a flight: what every caller (the plugin, ``check``,
    the reports, hypothesis targets) uses. ``margin`` > 0 inside the budget (SI)."""

    flight: str | None
    kpi: str
    budget: str
    op: str
    limit: float
    actual: float
    margin: float
    passed: bool
    actual_text: str
    margin_text: str

    @property
    def rel_margin(self) -> float:
        """margin / |limit| (margin itself for a zero limit)."""
        return self.margin / (abs(self.limit) if self.limit else 1.0)

    @property
    def verdict(self) -> str:
        """``"pass"`` or ``"fail"``."""
        return "pass" if self.passed else "fail"

    def to_dict(self) -> dict:
        """The JSON report's budget row (schema pytest-flockai/1)."""
        return {"flight": self.flight, "kpi": self.kpi, "budget": self.budget, "op": self.op,
                "limit": self.limit, "actual": self.actual, "margin": self.margin,
                "verdict": self.verdict, "actual_text": self.actual_text,
                "margin_text": self.margin_text}

    @classmethod
    def from_dict(cls, d: dict) -> Verdict:
        """From a report row (``to_dict``), e.g. one that came through pytest-xdist."""
        return cls(flight=d.get("flight"), kpi=d["kpi"], budget=d["budget"], op=d.get("op", ""),
                   limit=d.get("limit", math.nan), actual=d.get("actual", math.nan),
                   margin=d.get("margin", math.nan), passed=d["verdict"] == "pass",
                   actual_text=d.get("actual_text", str(d.get("actual"))),
                   margin_text=d.get("margin_text", str(d.get("margin"))))

    def __getitem__(self, key):
        """Dict-style access (``v["passed"]``, ``v["rel_margin"]``), as before 0.2."""
        return getattr(self, key)


def table(verdicts: Iterable[Verdict], indent: str = "  ") -> str:
    """The budget table of a failure message: flight, KPI, budget, actual, margin, verdict."""
    rows = [[v.flight or "", v.kpi, v.budget, v.actual_text, v.margin_text,
             "ok" if v.passed else "BROKEN"] for v in verdicts]
    return text_table(["flight", "KPI", "budget", "actual", "margin", "verdict"], rows, indent=indent)


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

    def __init__(self, message: str, verdicts: list[Verdict]) -> None:
        super().__init__(message)
        self.verdicts = verdicts


def evaluate(result: FlightResult | Mapping[str, float], budgets: dict | None = None,
             **more: str | Budget) -> list[Verdict]:
    """Evaluate budgets against a FlightResult (or a KPI dict) without pytest.

    Returns one ``Verdict`` per budget (kpi, budget, limit, actual, passed,
    margin: positive inside the budget, rel_margin: margin / |limit|).
    A budget on a KPI the flight did not produce raises ConfigError naming it.
    """
    kpis = getattr(result, "kpis", result)
    if not isinstance(kpis, Mapping):
        raise ConfigError(f"budgets.evaluate: result = {result!r} is not a FlightResult or a "
                          f"dict of KPIs")
    if budgets is not None and not isinstance(budgets, Mapping):
        raise ConfigError(f"budgets.evaluate: budgets = {budgets!r} is not allowed; expected a "
                          f"dict {{kpi: '<op> <number> [unit]'}}")
    spec = dict(budgets or {})
    spec.update(more)
    out = []
    for b in parse_many(spec):
        if b.kpi not in kpis:
            raise ConfigError(f"budget on {b.kpi!r}: the flight did not produce this KPI; it has "
                              f"{', '.join(sorted(kpis))}")
        out.append(b.verdict(kpis[b.kpi]))
    publish_verdicts(result, out)      # the plugin keeps them with the test (the reports)
    if not isinstance(result, Mapping):
        result.verdicts = tuple(out)   # shown by the result's _repr_html_ in a notebook
    return out


def check(result: FlightResult | Mapping[str, float], budgets: dict | None = None,
          **more: str | Budget) -> list[Verdict]:
    """Like ``evaluate`` but raises BudgetError (an AssertionError) with a table
    when a budget is broken: use it inside hypothesis ``@given`` tests, where
    the failing example is then shrunk and shown."""
    verdicts = evaluate(result, budgets, **more)
    broken = [v for v in verdicts if not v.passed]
    if broken:
        raise BudgetError(f"{len(broken)} of {len(verdicts)} KPI budget(s) broken:\n"
                          + table(verdicts), verdicts)
    return verdicts


__all__ = ["Budget", "BudgetError", "OPERATORS", "UNITS", "Verdict", "check", "evaluate", "kpi_unit",
           "parse", "parse_many", "table"]
