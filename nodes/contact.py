"""Where a collision was, as far as the robot can tell, and the map marks made from it.

A bumper says which of its segments closed; the IMU says which way the impact pushed. Either
gives a *contact arc*: a range of bearings (robot frame) on the body's edge. Placed with the
robot's own pose estimate it becomes a map-frame arc, and the obstacle is marked across that
arc (the chord plus a margin), so a corner or an oblique hit is covered and not a single
point straight ahead. A later hit near an existing mark grows that mark instead of starting
a new one.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

from bt_runtime.runtime.messages import wrap_angle


@dataclass(slots=True, frozen=True)
class ContactArc:
    """A sensed contact in the map frame: the robot's estimated centre (``x``, ``y``), the
    arc's middle ``bearing`` (map frame, rad) and ``half_width`` (rad), and the body
    ``radius`` (m) where the touch was; ``heading``, the robot's heading then (NaN: unknown)."""

    x: float
    y: float
    bearing: float
    half_width: float
    radius: float
    heading: float = math.nan

    def point_at(self, bearing: float, reach: float) -> tuple[float, float]:
        return self.x + reach * math.cos(bearing), self.y + reach * math.sin(bearing)

    def outward_side(self) -> int:
        """+1 / -1 when the arc lies on the robot's left / right front, clear of straight
        ahead; 0 otherwise (straight ahead, behind, or heading unknown)."""
        if not math.isfinite(self.heading):
            return 0
        rel = wrap_angle(self.bearing - self.heading)
        if self.half_width < abs(rel) <= math.pi / 2 + 1e-9:
            return 1 if rel > 0 else -1
        return 0

    def chord(self, reach: float, margin: float, outward: float = 0.0) -> list[tuple[float, float]]:
        """Points along the arc at distance ``reach`` from the robot's centre, extended by
        ``margin`` metres beyond each end, no further apart than ``margin`` (or 5 cm).

        ``outward`` m more beyond the end away from the robot's heading when the touch was off
        to one side of its front: an obstacle touched there lies on that side (had it reached
        across the robot's path, the front would have touched it first), so the rest of a box
        hit at its corner is covered and the re-plan passes on the free side."""
        reach = max(reach, 1e-6)
        lo = hi = margin / reach
        side = self.outward_side()
        if side > 0:
            hi += outward / reach
        elif side < 0:
            lo += outward / reach
        span = 2 * self.half_width + lo + hi
        spacing = max(min(margin, 0.1), 0.05)
        n = max(1, math.ceil(span * reach / spacing))
        start = self.bearing - self.half_width - lo
        return [self.point_at(start + span * i / n, reach) for i in range(n + 1)]

    def behind(self, points: list[tuple[float, float]], depth: float, step: float) -> list[tuple[float, float]]:
        """``points`` repeated in rows ``step`` apart up to ``depth`` m further along the arc's
        middle bearing (parallel rows, so the mark gets deeper, not wider). What stopped the
        robot has a body behind the surface it touched: a box touched at its corner or near an
        edge extends past the touched arc, and a re-plan that passes the mark's end and turns
        back behind it touches that part (the second touches of the collision variants)."""
        if depth <= 0 or step <= 0:
            return list(points)
        c, s = math.cos(self.bearing), math.sin(self.bearing)
        rows = max(1, math.ceil(depth / step - 1e-9))
        out = list(points)
        for k in range(1, rows + 1):
            d = min(depth, k * step)
            out.extend((x + d * c, y + d * s) for x, y in points)
        return out

    def to_string(self) -> str:
        text = f"{self.x:g};{self.y:g};{self.bearing:g};{self.half_width:g};{self.radius:g}"
        return text + (f";{self.heading:g}" if math.isfinite(self.heading) else "")


def segments_arc(spans: tuple[tuple[float, float], ...], pressed: tuple[int, ...]) -> tuple[float, float] | None:
    """(middle bearing, half width) in the robot frame covering every pressed segment, or None
    if no known segment is pressed. ``spans`` are (start, width) per segment."""
    known = [spans[i] for i in pressed if 0 <= i < len(spans)]
    if not known:
        return None
    x = y = 0.0
    for start, width in known:
        mid = start + width / 2
        x += width * math.cos(mid)
        y += width * math.sin(mid)
    if math.hypot(x, y) < 1e-9:  # opposite segments: the whole body
        return 0.0, math.pi
    middle = math.atan2(y, x)
    half = max(max(abs(wrap_angle(start - middle)), abs(wrap_angle(start + width - middle)))
               for start, width in known)
    return middle, min(half, math.pi)


@dataclass(slots=True)
class Mark:
    """One obstacle as marked in the map: the discs sent to navigation (``discs``), its *core*,
    the discs over what was sensed alone (the touched arc and the body behind it, no margins),
    and its *touch*, a disc at each sensed contact's middle: what stays when the mark is relaxed
    once, then twice, because it closes the only way (``stage`` 0, 1, 2)."""

    discs: list[tuple[float, float, float]] = field(default_factory=list)  # (x, y, radius)
    core: list[tuple[float, float, float]] = field(default_factory=list)
    touch: list[tuple[float, float, float]] = field(default_factory=list)
    stage: int = 0

    def distance_to(self, x: float, y: float) -> float:
        return min(math.hypot(x - dx, y - dy) - r for dx, dy, r in self.discs)


class ObstacleMarks:
    """The marks made so far (kept on ``context.extras['collision_marks']``)."""

    def __init__(self) -> None:
        self.marks: list[Mark] = []

    def place(self, points: list[tuple[float, float]], radius: float, merge_distance: float,
              core: list[tuple[float, float, float]] | None = None,
              touch: list[tuple[float, float, float]] | None = None) -> tuple[int, list[tuple[float, float, float]]]:
        """Add discs of ``radius`` at ``points``: to the mark that lies within
        ``merge_distance`` of any of them (that mark grows), else as a new mark; ``core`` (the
        discs over what was sensed alone) and ``touch`` (the contact's middle) join the mark's.
        Returns the mark's index and the discs that are new."""
        target = None
        for i, mark in enumerate(self.marks):
            if any(mark.distance_to(x, y) <= merge_distance + radius for x, y in points):
                target = i
                break
        if target is None:
            self.marks.append(Mark())
            target = len(self.marks) - 1
        mark = self.marks[target]
        new = [(x, y, radius) for x, y in points
               if not any(math.hypot(x - dx, y - dy) < 0.5 * radius for dx, dy, _ in mark.discs)]
        mark.discs.extend(new)
        mark.core.extend(core if core is not None else [(x, y, radius) for x, y in points])
        mark.touch.extend(touch if touch is not None else mark.core[-1:])
        if new:
            mark.stage = 0
        return target, new

    def relax(self) -> bool:
        """Shrink every mark one stage: to its core, then to its touches. True if any mark
        changed (then the map must be marked again from ``discs()``)."""
        changed = False
        for mark in self.marks:
            while mark.stage < 2:
                mark.stage += 1
                smaller = mark.core if mark.stage == 1 else mark.touch
                if smaller and smaller != mark.discs:
                    mark.discs = list(smaller)
                    changed = True
                    break
        return changed

    def discs(self) -> list[tuple[float, float, float]]:
        return [d for mark in self.marks for d in mark.discs]


def marks_of(context) -> ObstacleMarks:
    extras = context.extras
    marks = extras.get("collision_marks")
    if not isinstance(marks, ObstacleMarks):
        marks = extras["collision_marks"] = ObstacleMarks()
    return marks
