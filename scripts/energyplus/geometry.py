"""Rectangular geometry of our models, in world coordinates (x east, y north, z up, metres).

Surfaces follow EnergyPlus's ``UpperLeftCorner, Counterclockwise`` vertex rule: a surface lists
its corners anticlockwise as seen from outside, starting at the upper-left one. A vertical
rectangle is given by its two bottom corners in the order left → right as seen from outside,
which also fixes its outward normal (the left→right direction turned 90° clockwise in plan).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

Point2 = tuple[float, float]
Point3 = tuple[float, float, float]


@dataclass(frozen=True)
class VerticalRect:
    """A vertical rectangle between two bottom corners (left → right seen from outside).

    left, right : plan coordinates of the bottom corners. [m]
    z_bottom, z_top : heights of the bottom and top edges. [m]
    """

    left: Point2
    right: Point2
    z_bottom: float
    z_top: float

    @property
    def width(self) -> float:
        return math.dist(self.left, self.right)

    @property
    def area(self) -> float:
        return self.width * (self.z_top - self.z_bottom)

    @property
    def azimuth(self) -> float:
        """Azimuth of the outward normal, clockwise from north (pvlib's convention). [°]"""
        dx, dy = self.right[0] - self.left[0], self.right[1] - self.left[1]
        normal_x, normal_y = dy, -dx  # left→right direction turned 90° clockwise
        return math.degrees(math.atan2(normal_x, normal_y)) % 360.0

    def vertices(self) -> list[Point3]:
        (x0, y0), (x1, y1) = self.left, self.right
        return [
            (x0, y0, self.z_top),
            (x0, y0, self.z_bottom),
            (x1, y1, self.z_bottom),
            (x1, y1, self.z_top),
        ]

    def window(self, width: float, sill: float, head: float) -> VerticalRect:
        """A centred opening of ``width`` between heights ``sill`` and ``head``. [m]"""
        margin = (self.width - width) / 2.0
        if margin <= 0.0 or not self.z_bottom < sill < head < self.z_top:
            raise ValueError(f"window {width} x ({sill}..{head}) m does not fit in the wall")
        ux = (self.right[0] - self.left[0]) / self.width
        uy = (self.right[1] - self.left[1]) / self.width
        left = (self.left[0] + margin * ux, self.left[1] + margin * uy)
        right = (self.right[0] - margin * ux, self.right[1] - margin * uy)
        return VerticalRect(left, right, sill, head)


@dataclass(frozen=True)
class Box:
    """A rectangular zone: plan x0..x1 (west → east), y0..y1 (south → north), height, floor
    level z0. [m]"""

    x0: float
    x1: float
    y0: float
    y1: float
    height: float
    z0: float = 0.0

    @property
    def floor_area(self) -> float:
        return (self.x1 - self.x0) * (self.y1 - self.y0)

    @property
    def volume(self) -> float:
        return self.floor_area * self.height

    def wall(self, side: str) -> VerticalRect:
        """The wall facing ``side`` (north, east, south or west)."""
        corners = {
            "south": ((self.x0, self.y0), (self.x1, self.y0)),
            "east": ((self.x1, self.y0), (self.x1, self.y1)),
            "north": ((self.x1, self.y1), (self.x0, self.y1)),
            "west": ((self.x0, self.y1), (self.x0, self.y0)),
        }
        left, right = corners[side]
        return VerticalRect(left, right, self.z0, self.z0 + self.height)

    def roof(self) -> list[Point3]:
        h = self.z0 + self.height
        return [
            (self.x0, self.y1, h),
            (self.x0, self.y0, h),
            (self.x1, self.y0, h),
            (self.x1, self.y1, h),
        ]

    def floor(self) -> list[Point3]:
        z = self.z0
        return [
            (self.x1, self.y1, z),
            (self.x1, self.y0, z),
            (self.x0, self.y0, z),
            (self.x0, self.y1, z),
        ]


SIDES = ("north", "east", "south", "west")
