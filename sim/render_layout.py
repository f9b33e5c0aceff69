"""Where things go on a rendered picture: the map area in pixels, axes ticks, fonts.

Kept apart from the drawing so a test (or a caller adding its own layer) can turn a map
point into the exact pixel the renderer uses: ``Layout(world.bounds, scale).px(x, y)``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import lru_cache

from PIL import ImageFont

TITLE_H = 48  # two lines of title text
AXIS_LEFT = 52  # y tick labels and the "y [m]" label
AXIS_BOTTOM = 46  # x tick labels, "x [m]" and the scale bar
PAD = 12
LEGEND_W = 210


@lru_cache(maxsize=8)
def font(size: int = 14) -> ImageFont.ImageFont:
    """Pillow's bundled scalable font at ``size`` px (readable, no system font needed)."""
    return ImageFont.load_default(size=size)


def tick_step(span_m: float, scale: float, min_px: float = 60.0) -> float:
    """The smallest of 0.5, 1, 2, 5, 10, ... m whose ticks are at least ``min_px`` apart."""
    for step in (0.5, 1.0, 2.0, 5.0, 10.0, 20.0, 50.0, 100.0):
        if step * scale >= min_px:
            return step
    return 10 ** math.ceil(math.log10(max(span_m, 1.0)))


@dataclass(frozen=True)
class Layout:
    """Title on top, the map framed by axes in metres, the legend on the right."""

    xmin: float
    ymin: float
    xmax: float
    ymax: float
    scale: float  # pixels per metre

    @classmethod
    def of(cls, bounds, scale: float) -> Layout:
        return cls(bounds.xmin, bounds.ymin, bounds.xmax, bounds.ymax, float(scale))

    @property
    def map_w(self) -> int:
        return int(math.ceil((self.xmax - self.xmin) * self.scale))

    @property
    def map_h(self) -> int:
        return int(math.ceil((self.ymax - self.ymin) * self.scale))

    @property
    def left(self) -> int:
        return PAD + AXIS_LEFT

    @property
    def top(self) -> int:
        return TITLE_H + PAD

    @property
    def width(self) -> int:
        return self.left + self.map_w + PAD + LEGEND_W

    @property
    def height(self) -> int:
        return max(self.top + self.map_h + AXIS_BOTTOM + PAD, self.top + 260)

    def px(self, x: float, y: float) -> tuple[float, float]:
        """The pixel (column, row) of the map point (x, y) in metres."""
        return (self.left + (x - self.xmin) * self.scale, self.top + (self.ymax - y) * self.scale)

    def ticks(self, lo: float, hi: float) -> list[float]:
        step = tick_step(hi - lo, self.scale)
        first = math.ceil(lo / step - 1e-9) * step
        n = int(math.floor((hi - first) / step + 1e-9)) + 1
        return [round(first + i * step, 6) for i in range(max(0, n))]
