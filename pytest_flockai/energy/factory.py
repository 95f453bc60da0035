"""The energy model of one flight, built from the drone's own model.

The drone's model (``drone.energy``, built from its blueprint's parameters)
is left untouched; a flight gets a copy when it differs: the power of sensors
added to the drone or the mission goes into ``proc.sensors``, and the computer
the on-board tasks run on becomes ``proc.soc`` when it is not the blueprint's,
and the blueprint's own computer stays on board, idle, as ``proc.soc_blueprint``
(a task that names another computer adds one; it does not take the drone's away).
"""

from __future__ import annotations

from .components import Constant, SoC
from .tree import Group


def flight_energy_model(base, *, extra_sensors=(), device=None, blueprint_device: str = "none"):
    """``base``: the drone's EnergyModel; ``extra_sensors``: sensor objects with a
    ``power_w``; ``device``: the on-board computer of this flight (a compute
    Device) or None; ``blueprint_device``: the blueprint's device name."""
    extra = [sn for sn in extra_sensors if getattr(sn, "power_w", 0.0) > 0.0]
    swap_soc = device is not None and device.name != blueprint_device
    if not extra and not swap_soc:
        return base
    model = base.copy()
    if swap_soc and "proc" in model:
        proc = model.component("proc")
        soc = SoC.of(device, ", added for the tasks")
        if "soc" in proc:
            own = proc.component("soc")
            proc.replace("soc", soc)
            proc.add(Constant("soc_blueprint", getattr(own, "idle_w", 0.0),
                              f"the blueprint's on-board computer {blueprint_device}, idle"))
        else:
            proc.add(soc)
    if not extra:
        return model
    proc = model.component("proc") if "proc" in model else None
    if proc is None:
        proc = Group("proc")
        model.add(proc)
    if "sensors" not in proc:
        proc.add(Group("sensors"))
    group = proc.component("sensors")
    for sn in extra:
        if sn.name not in group:
            group.add(Constant(sn.name, sn.power_w, f"{type(sn).__name__} sensor"))
    return model


def carry_computer(model, dev) -> None:
    """The energy model ``model``'s on-board computer (``proc.soc``) becomes ``dev``'s (a
    compute ``Device``; None: no computer): its idle power all flight, its busy power while
    tasks compute."""
    proc = model.component("proc") if "proc" in model else None
    if not isinstance(proc, Group):
        return
    if dev is None:
        if "soc" in proc:
            proc.remove("soc")
        return
    soc = SoC.of(dev)
    if "soc" in proc:
        proc.replace("soc", soc)
    else:
        proc.add(soc)
