"""What a policy's ``Cockpit`` hands it: a delivered task result, the radio link."""

from __future__ import annotations


class Delivered:
    """One task result as the drone receives it: ``task``, ``t_capture``,
    ``t_delivered``, ``ok``, ``detections`` (``ml.detections.Detections`` above the
    task's score threshold, or None for outputs that are not boxes), ``count``
    (the task's count of the prediction), ``nav`` (x, y, z, qw, qx, qy, qz) the
    drone believed at capture, ``prediction`` (the model's raw output)."""

    __slots__ = ("task", "t_capture", "t_delivered", "ok", "detections", "count", "nav",
                 "prediction")

    def __init__(self, **kw):
        for k in self.__slots__:
            setattr(self, k, kw.get(k))

    def __repr__(self):
        n = None if self.detections is None else len(self.detections)
        return (f"Delivered({self.task!r}, captured {self.t_capture:.2f} s, delivered "
                f"{self.t_delivered:.2f} s, detections={n})")


class Link:
    """The radio as the drone sees it: ``distance_m`` to the ground station,
    ``range_m`` of the link, ``in_range``."""

    __slots__ = ("distance_m", "range_m", "in_range")

    def __init__(self, distance_m, range_m):
        self.distance_m, self.range_m = distance_m, range_m
        self.in_range = distance_m <= range_m


__all__ = ["Delivered", "Link"]
