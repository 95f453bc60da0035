"""The battery as an equivalent circuit: open-circuit voltage and internal resistance.

Each cell is a voltage source OCV(s), s the state of charge in [0, 1], behind a
DC resistance R(s). ``cells`` of them in series deliver the load power P at the
terminals: P = (OCV - I R) I, so the current is

    I = (OCV - sqrt(OCV^2 - 4 R P)) / (2 R)

and the terminal voltage sags to OCV - I R. The cell loses I^2 R as heat; the
chemical energy drawn is OCV x I (the load's power plus the loss). A flight on
this battery ends when its charge reaches the usable floor (``1 -
usable_fraction``: the battery management system's 0 %) or when the terminal
voltage under load falls below the cut-off voltage, whichever comes first.

Open-circuit voltage per cell:

- ``lipo``: Chen and Rincon-Mora, "Accurate electrical battery model capable of
  predicting runtime and I-V performance", IEEE Trans. Energy Conversion 21(2),
  2006, eq. (1)-(2), fitted on a lithium-ion polymer cell (TCL PL-383562):
  OCV(s) = -1.031 exp(-35 s) + 3.685 + 0.2156 s - 0.1178 s^2 + 0.3201 s^3 V
  (4.10 V full, 3.80 V at half charge). The shape of their series resistance,
  0.07446 + 0.1562 exp(-24.37 s) ohm, scales our mid-charge resistance so it
  rises as the cell empties.
- ``li-ion``: Tremblay, Dessaint and Dekkiche, "A generic battery model for the
  dynamic simulation of hybrid electric vehicles", IEEE VPPC 2007, Li-ion
  3.6 V 1 Ah cell: OCV = E0 - K / s + A exp(-B (1 - s) Q) with E0 = 3.7348 V,
  K = 0.00876 V, A = 0.468 V, B = 3.5294 /Ah, Q = 1 Ah (4.19 V full, 3.80 V
  at half charge); the same resistance shape as above.

Cut-off voltages per cell: 3.0 V for LiPo and 2.5 V for Li-ion, the discharge
cut-off of the cells' datasheets (e.g. Samsung INR18650-25R: 2.5 V; LiPo
pouch cells such as Grepow or Tattu: 3.0 V). The flight ends when the terminal
voltage stays below it for ``CUTOFF_HOLD_S`` (a take-off punch of a fraction of
a second does not end it, as a flight controller's filtered voltage would not),
or at once when the load asks for more power than the pack can give.
"""

from __future__ import annotations

import functools
import math
from typing import NamedTuple

from .._xp import MATH

CHEMISTRIES = ("lipo", "li-ion")

#: V per cell, discharge cut-off from the cell datasheets (see the module docstring)
CUTOFF_V = {"lipo": 3.0, "li-ion": 2.5}

#: V per cell, the nominal voltage a pack's label uses (cells = nominal / this)
NOMINAL_V = {"lipo": 3.7, "li-ion": 3.6}

#: ohm x Ah, DC resistance of one cell at half charge times its capacity. An
#: estimate for drone packs: Chen and Rincon-Mora's 850 mAh phone cell has about
#: 0.15 ohm x Ah (series plus both RC branches, 1C cell); multirotor packs are
#: high-rate (10-25C) cells of 3-8 mOhm at 3-5 Ah, about 0.02-0.03 ohm x Ah.
SPECIFIC_RESISTANCE_OHM_AH = 0.03

#: s the terminal voltage must stay below the cut-off before the flight ends
CUTOFF_HOLD_S = 1.0


def ocv_lipo(s, xp=MATH):
    """Open-circuit voltage of one LiPo cell (V) at state of charge ``s`` (Chen and Rincon-Mora)."""
    return -1.031 * xp.exp(-35.0 * s) + 3.685 + s * (0.2156 + s * (-0.1178 + s * 0.3201))


def ocv_liion(s, xp=MATH):
    """Open-circuit voltage of one Li-ion cell (V) at state of charge ``s`` (Tremblay et al.)."""
    s = xp.maximum(s, 1e-3)
    return 3.7348 - 0.00876 / s + 0.468 * xp.exp(-3.5294 * (1.0 - s))


def ocv(chemistry: str, s: float) -> float:
    """Open-circuit voltage of one cell (V) at state of charge ``s``."""
    return ocv_lipo(s) if chemistry == "lipo" else ocv_liion(s)


def resistance_shape(s, xp=MATH):
    """R(s) / R(0.5): Chen and Rincon-Mora's series resistance, normalised at half charge."""
    return (0.07446 + 0.1562 * xp.exp(-24.37 * s)) / (0.07446 + 0.1562 * math.exp(-12.185))


def terminal_current(e, r, power_w, xp=MATH):
    """(current I, over) drawn from a source ``e`` behind ``r`` by a load of ``power_w``:
    I = (e - sqrt(e^2 - 4 r P)) / 2r; ``over`` where P is beyond the pack's maximum
    power (then I = e / 2r, the current of that maximum)."""
    disc = e * e - 4.0 * r * power_w
    over = disc < 0.0
    i = xp.where(over, e / (2.0 * r), xp.where(
        power_w > 0.0, (e - xp.sqrt(xp.maximum(disc, 0.0))) / (2.0 * r), 0.0))
    return i, over


class BatteryParams(NamedTuple):
    """A pack's circuit as numbers (``Circuit.batch_params``): what the batched backend flies."""

    lipo: bool
    cells: float
    q_c: float
    r_mid: float
    v_cut: float
    v0: float


@functools.lru_cache(maxsize=512)
def usable_energy_j(chemistry: str, cells: int, capacity_ah: float, floor: float, n: int = 400) -> float:
    """Chemical energy (J) between full charge and the floor: cells x Q x integral of OCV ds."""
    h = (1.0 - floor) / n
    acc = 0.5 * (ocv(chemistry, floor) + ocv(chemistry, 1.0))
    for k in range(1, n):
        acc += ocv(chemistry, floor + k * h)
    return cells * capacity_ah * 3600.0 * acc * h


class Circuit:
    """The pack in flight: ``draw(power_w, dt)`` takes the load's power for dt seconds
    and returns the I^2 R loss (W); ``voltage_v``, ``current_a``, ``soc`` and
    ``cutoff`` (the terminal voltage fell below the cut-off, or the load asked for
    more than the pack can give) describe it after the draw."""

    def __init__(self, *, chemistry: str, cells: int, capacity_ah: float, resistance_ohm: float,
                 cutoff_v_per_cell: float):
        self.chemistry = chemistry
        self.cells = cells
        self.q_c = capacity_ah * 3600.0
        self.r_mid = resistance_ohm * cells                 # pack, at half charge
        self.v_cut = cutoff_v_per_cell * cells
        self.soc = 1.0
        self.current_a = 0.0
        self.voltage_v = self.open_circuit_v()
        self.cutoff = False
        self.v_min = self.voltage_v
        self._below_s = 0.0

    def batch_params(self) -> BatteryParams:
        """The circuit's constants, for the batched backend (the state starts full)."""
        return BatteryParams(lipo=self.chemistry == "lipo", cells=float(self.cells), q_c=self.q_c,
                             r_mid=self.r_mid, v_cut=self.v_cut, v0=self.cells * ocv(self.chemistry, 1.0))

    def open_circuit_v(self) -> float:
        return self.cells * ocv(self.chemistry, self.soc)

    def draw(self, power_w: float, dt: float) -> float:
        e = self.open_circuit_v()
        r = self.r_mid * resistance_shape(self.soc)
        i, over = terminal_current(e, r, power_w)
        if over:                       # beyond the pack's maximum power (at I = E / 2R)
            self.cutoff = True
        v = e - i * r
        self.current_a, self.voltage_v = i, v
        if v < self.v_min:
            self.v_min = v
        if i > 0.0 and v < self.v_cut:
            self._below_s += dt
            if self._below_s >= CUTOFF_HOLD_S - 1e-9:
                self.cutoff = True
        else:
            self._below_s = 0.0
        self.soc -= i * dt / self.q_c
        return i * i * r
