"""Composition of energy components (paper section 4.4, Listing 4).

``EnergyModel`` is a tree: the top groups ``motors``, ``proc`` and ``comm``;
groups hold components or more groups. Users inspect, replace, remove and add::

    proc = drone.energy.component("proc")
    proc.remove("sensors", "io")
    proc.component("fc").set_description("DJI A3 flight controller").set_power(8.3)
    drone.energy.replace("proc", proc)       # or edit in place, as above

During a flight a ``Meter`` integrates every leaf part on the simulated clock.
"""

from __future__ import annotations

import copy

from ..errors import ConfigError, close_matches
from ..physics import RHO_SEA_LEVEL
from .components import Component, Constant, RadioLinear, SoC, Usage
from .rotors import MOTOR_FIELDS, Motors


class Group(Component):
    """A named group of components; its power is the sum of its children."""

    def __init__(self, name: str, children=(), description: str = ""):
        super().__init__(name, description)
        self._children: dict[str, Component] = {}
        for c in children:
            self.add(c)

    # inspection --------------------------------------------------------
    def names(self) -> list[str]:
        return list(self._children)

    @property
    def children(self) -> list[Component]:
        return list(self._children.values())

    def component(self, path: str) -> Component:
        """The child named ``path``; dotted paths reach deeper ("proc.fc")."""
        head, _, rest = str(path).partition(".")
        child = self._children.get(head)
        if child is None:
            raise ConfigError(f"energy group {self.name!r} has no component {head!r}"
                              f"{close_matches(head, self._children)}; it has: "
                              f"{', '.join(self._children) or '(nothing)'}")
        if rest:
            if not isinstance(child, Group):
                raise ConfigError(f"energy component {self.name}.{head} is not a group; "
                                  f"cannot look up {rest!r} in it")
            return child.component(rest)
        return child

    def __contains__(self, name) -> bool:
        return name in self._children

    # editing -----------------------------------------------------------
    def add(self, comp: Component) -> Group:
        if not isinstance(comp, Component):
            raise ConfigError(f"energy group {self.name!r}: add() takes a Component, got {comp!r}")
        if comp.name in self._children:
            raise ConfigError(f"energy group {self.name!r} already has a component {comp.name!r}; "
                              f"use replace({comp.name!r}, ...)")
        self._children[comp.name] = comp
        return self

    def remove(self, *names) -> Group:
        flat = []
        for n in names:
            flat.extend([n] if isinstance(n, str) else list(n))
        for n in flat:
            if n not in self._children:
                raise ConfigError(f"energy group {self.name!r} has no component {n!r} to remove"
                                  f"{close_matches(n, self._children)}; it has: "
                                  f"{', '.join(self._children) or '(nothing)'}")
        for n in flat:
            del self._children[n]
        return self

    def replace(self, name: str, comp: Component) -> Group:
        if name not in self._children:
            raise ConfigError(f"energy group {self.name!r} has no component {name!r} to replace"
                              f"{close_matches(name, self._children)}; it has: "
                              f"{', '.join(self._children)}")
        if not isinstance(comp, Component):
            raise ConfigError(f"energy group {self.name!r}: replace() takes a Component, got {comp!r}")
        items = [(comp.name if k == name else k, comp if k == name else v)
                 for k, v in self._children.items()]
        self._children = dict(items)
        return self

    # paper-style aliases (Listing 4)
    removeComponents = remove
    getComponent = component
    updComponent = replace

    def copy(self) -> Group:
        return copy.deepcopy(self)

    def bind(self, drone):
        for c in self._children.values():
            c.bind(drone)

    def bind_air_density(self, rho):
        for c in self._children.values():
            c.bind_air_density(rho)

    def power(self, u):
        return sum(c.power(u) for c in self._children.values())

    def describe(self) -> dict:
        out = super().describe()
        out["components"] = [c.describe() for c in self._children.values()]
        return out

    def leaves(self, prefix: str = ""):
        """(path, component) for every non-group component, depth first."""
        for c in self._children.values():
            path = f"{prefix}{c.name}"
            if isinstance(c, Group):
                yield from c.leaves(path + ".")
            else:
                yield path, c

    def __repr__(self):
        return f"Group({self.name!r}, [{', '.join(self._children)}])"


class EnergyModel(Group):
    """The drone's energy model: total = motors + proc + comm (+ whatever users add)."""

    def __init__(self, children=(), description="E_total = E_motors + E_proc + E_comm"):
        super().__init__("total", children, description)

    @classmethod
    def from_params(cls, p, *, device, radio) -> EnergyModel:
        """The model built from a blueprint's ``[energy]`` parameters ``p``, its
        on-board computer ``device`` (a ``compute.Device`` or None) and its
        ``radio`` section."""
        motors = Motors("motors", figure_of_merit=p.figure_of_merit,
                        induced_power_factor=p.induced_power_factor,
                        motor_efficiency=p.motor_efficiency, esc_efficiency=p.esc_efficiency,
                        wake_interference=p.wake_interference,
                        **{k: getattr(p, k) for k in MOTOR_FIELDS})
        proc = Group("proc", description="processing: flight controller, SoC, I/O, sensors")
        proc.add(Constant("fc", p.flight_controller_w, "flight controller"))
        if device is not None:
            proc.add(SoC.of(device))
        proc.add(Constant("io", p.io_w, "storage and buses"))
        proc.add(Group("sensors", [Constant(k, v, f"{k} sensor") for k, v in p.sensors.items()],
                       "sensor power"))
        r = radio
        comm = Group("comm", [RadioLinear(
            "radio", tx_uj_per_byte=r.tx_uj_per_byte, tx_uj_per_packet=r.tx_uj_per_packet,
            rx_uj_per_byte=r.rx_uj_per_byte, rx_uj_per_packet=r.rx_uj_per_packet,
            idle_w=r.idle_w, description="radio link to the ground station")],
            "communication")
        return cls([motors, proc, comm])


class Meter:
    """Integrates every leaf part of an energy model over a flight.

    ``step(usage)`` returns the total power of the tick and adds energy to each
    part; ``parts`` names them ("motors.induced", "proc.fc", ...). The load's
    power is drawn from the drone's battery circuit (``battery``, see
    ``energy/battery.py``): its I^2 R loss is not a load (E_total stays
    E_motors + E_proc + E_comm) but drains the battery too; ``loss_j`` sums it and
    ``last_loss`` is the loss of the last tick (W).
    """

    def __init__(self, model: EnergyModel, drone, rho: float = RHO_SEA_LEVEL):
        model.bind_air_density(rho)
        model.bind(drone)
        self.battery = drone.battery.circuit()
        self.model = model
        self._leaves = []
        self.parts: list[str] = []
        for path, comp in model.leaves():
            if comp.parts:
                self._leaves.append((comp.power_parts, len(comp.parts)))
                self.parts.extend(f"{path}.{p}" for p in comp.parts)
            else:
                self._leaves.append((comp.power, 0))
                self.parts.append(path)
        self.energy = [0.0] * len(self.parts)
        self.loss_j = 0.0
        self.last_loss = 0.0
        self.top = [p.split(".", 1)[0] for p in self.parts]
        tops = list(dict.fromkeys(self.top))
        self._top_idx = [(name, [i for i, t in enumerate(self.top) if t == name]) for name in tops]
        self.last_power = 0.0

    def step(self, u: Usage) -> float:
        dt = u.dt
        e = self.energy
        k = 0
        total = 0.0
        for fn, n in self._leaves:
            if n:
                for p in fn(u):
                    e[k] += p * dt
                    total += p
                    k += 1
            else:
                p = fn(u)
                e[k] += p * dt
                total += p
                k += 1
        loss = self.battery.draw(total, dt)
        self.loss_j += loss * dt
        self.last_loss = loss
        self.last_power = total
        return total

    def totals_by_top(self) -> dict[str, float]:
        """Energy (J) of each top group ("motors", "proc", "comm", ...)."""
        e = self.energy
        out = {}
        for name, idx in self._top_idx:
            total = 0.0
            for i in idx:
                total += e[i]
            out[name] = total
        return out

    def breakdown(self) -> dict[str, float]:
        """Energy (J) of every part and every group on the path to it."""
        out: dict[str, float] = {}
        for name, e in zip(self.parts, self.energy):
            bits = name.split(".")
            for i in range(1, len(bits) + 1):
                key = ".".join(bits[:i])
                out[key] = out.get(key, 0.0) + e
        return out
