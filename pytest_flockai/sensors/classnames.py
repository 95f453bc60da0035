"""Class names matched by name, never by position: a dataset's categories to a task's classes.

A label file names its categories (COCO ``categories``, YOLO ``classes.txt`` or
``data.yaml`` ``names``, VisDrone's fixed list); a task names the classes its
model's class indices stand for. ``class_map(source, task_classes)`` pairs them:

1. the same name (case, spaces, ``_`` and ``-`` ignored): ``Person`` is ``person``;
2. else the stated ``ALIASES``: a dataset's narrower name scored as the task's
   broader class (``car`` is scored as ``vehicle``, ``pedestrian`` as ``person``).
   The vehicle names are COCO's "vehicle" supercategory on the road (bicycle, car,
   motorcycle, bus, truck; COCO 2017 ``instances_*.json`` categories) and
   VisDrone-DET's road users (bicycle, car, van, truck, tricycle, awning-tricycle,
   bus, motor; Zhu et al., "Detection and Tracking Meet Drones Challenge", TPAMI
   2021, table 1); its "pedestrian" and "people" are both persons;
3. ``IGNORE_NAMES`` (VisDrone's "ignored regions" and "others") become ignore
   regions of every task class: a detection there is neither rewarded nor punished.

A dataset category that matches no task class is not scored (a person task on
frames that also show vehicles). A task class that no category matches is a
ConfigError (the model's class would be scored against nothing), and so are
two task classes that are the same name.
"""

from __future__ import annotations

import numpy as np

from ..errors import ConfigError

#: a dataset's name -> the class it is scored as when the task does not name it
ALIASES = {
    "pedestrian": "person", "people": "person", "persons": "person", "human": "person",
    "bicycle": "vehicle", "car": "vehicle", "motorcycle": "vehicle", "motorbike": "vehicle",
    "motor": "vehicle", "bus": "vehicle", "truck": "vehicle", "van": "vehicle",
    "tricycle": "vehicle", "awningtricycle": "vehicle",
}
#: dataset names that mark ignore regions (VisDrone-DET categories 0 and 11)
IGNORE_NAMES = ("ignoredregions", "ignoredregion", "others")
#: class_map's code for a category that is an ignore region of every task class
IGNORE = -2


def normalise(name) -> str:
    """The name compared: lower case, without spaces, ``_`` and ``-``."""
    return "".join(ch for ch in str(name).lower() if ch not in " _-")


def class_map(source, task_classes, where: str) -> np.ndarray:
    """For each ``source`` name, the index of the task class it is scored as, -1 (not
    scored) or ``IGNORE``; ConfigError for a task class no source name matches."""
    task_norm = [normalise(c) for c in task_classes]
    for i, n in enumerate(task_norm):
        if n in task_norm[:i]:
            raise ConfigError(f"{where}: classes {task_classes[task_norm.index(n)]!r} and "
                              f"{task_classes[i]!r} are the same name; a name may appear once")
    out = np.full(len(source), -1, dtype=int)
    for k, name in enumerate(source):
        n = normalise(name)
        if n in task_norm:
            out[k] = task_norm.index(n)
        elif n in IGNORE_NAMES:
            out[k] = IGNORE
        elif ALIASES.get(n) in task_norm:
            out[k] = task_norm.index(ALIASES[n])
    missing = [c for i, c in enumerate(task_classes) if i not in out]
    if missing:
        raise ConfigError(f"{where}: class {missing[0]!r} matches no category of the labels "
                          f"({', '.join(map(str, source)) or 'none'}); name it as the labels do, "
                          f"or by an alias ({_alias_text()})")
    return out


def _alias_text() -> str:
    by: dict = {}
    for a, c in ALIASES.items():
        by.setdefault(c, []).append(a)
    return "; ".join(f"{c}: {', '.join(v)}" for c, v in by.items())


def person_index(source) -> np.ndarray:
    """Indices of the ``source`` names that are people (``person`` or an alias of it)."""
    return np.array([k for k, n in enumerate(source)
                     if normalise(n) == "person" or ALIASES.get(normalise(n)) == "person"], dtype=int)


def to_task_classes(objs, task_classes, where: str, cache: dict):
    """``objs`` (world.truth.Objects in their own class names) in the task's class
    indices: unscored rows dropped, ignore regions repeated for every task class
    (visible 0). ``cache``: the caller's dict of class maps by source names."""
    src = tuple(objs.classes)
    if src == tuple(task_classes):
        return objs
    if src not in cache:
        cache[src] = class_map(src, task_classes, where)
    m = cache[src][objs.cls] if len(objs) else np.zeros(0, dtype=int)
    keep = np.flatnonzero(m >= 0)
    ign = np.flatnonzero(m == IGNORE)
    rows = np.concatenate([keep, np.repeat(ign, len(task_classes))])
    cls = np.concatenate([m[keep], np.tile(np.arange(len(task_classes)), len(ign))])
    vis = objs.visible[rows].copy()
    vis[len(keep):] = 0.0
    return type(objs)(ids=objs.ids[rows], cls=cls.astype(int), boxes=objs.boxes[rows],
                      visible=vis, distance_m=objs.distance_m[rows], gsd_m=objs.gsd_m[rows],
                      classes=tuple(task_classes))
