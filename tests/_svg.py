"""Reading matplotlib SVGs back: artists by ``gid``, and data coordinates from an axes' ticks.

matplotlib writes an artist with ``gid`` as ``<g id="gid">``; markers are ``<use x= y=>``, paths
``<path d="M x y L …">`` in SVG points. With ``svg.fonttype = none`` a tick label is a
``<text>`` holding its value, so the ticks of an axes give the data → SVG map (x and y are
each affine), independently of the artists being checked.
"""

from __future__ import annotations

import re
import xml.etree.ElementTree as ET

import numpy as np

SVG = "{http://www.w3.org/2000/svg}"


class SvgFigure:
    def __init__(self, text: str | bytes) -> None:
        self.root = ET.fromstring(text)
        self.groups = {g.get("id"): g for g in self.root.iter(f"{SVG}g") if g.get("id")}

    def group(self, gid: str) -> ET.Element:
        return self.groups[gid]

    def has(self, gid: str) -> bool:
        return gid in self.groups

    def ids(self, prefix: str) -> list[str]:
        return [i for i in self.groups if i.startswith(prefix)]

    def uses(self, gid: str) -> np.ndarray:
        """Marker positions (N, 2) [SVG pt] of the artist ``gid``, in drawing order."""
        pts = [(float(u.get("x")), float(u.get("y"))) for u in self.group(gid).iter(f"{SVG}use")]
        return np.array(pts).reshape(-1, 2)

    def path_points(self, gid: str) -> np.ndarray:
        """Vertices (N, 2) [SVG pt] of the first path of the artist ``gid``."""
        path = next(self.group(gid).iter(f"{SVG}path"))
        numbers = [float(v) for v in re.findall(r"-?\d+(?:\.\d+)?(?:e-?\d+)?", path.get("d"))]
        return np.array(numbers).reshape(-1, 2)

    def texts(self, gid: str | None = None) -> list[str]:
        root = self.root if gid is None else self.group(gid)
        return ["".join(t.itertext()) for t in root.iter(f"{SVG}text")]

    def axes_map(self, axes_gid: str) -> tuple[np.ndarray, np.ndarray]:
        """``(ax, ay)``: SVG x = ax[0]·x + ax[1], SVG y = ay[0]·y + ay[1] from the tick labels."""
        axes = self.group(axes_gid)
        fits = []
        for axis, coordinate in (("xtick", 0), ("ytick", 1)):
            values, positions = [], []
            for g in axes.iter(f"{SVG}g"):
                if not (g.get("id") or "").startswith(axis):
                    continue
                label = "".join(next(g.iter(f"{SVG}text")).itertext()).replace("−", "-")
                mark = next(g.iter(f"{SVG}use"))
                values.append(float(label))
                positions.append(float(mark.get("x" if coordinate == 0 else "y")))
            assert len(values) >= 2, f"{axes_gid}: fewer than two {axis}s"
            fits.append(np.polyfit(values, positions, 1))
        return fits[0], fits[1]

    def to_data(self, axes_gid: str, points: np.ndarray) -> np.ndarray:
        """SVG points (N, 2) → the axes' data coordinates."""
        ax, ay = self.axes_map(axes_gid)
        return np.column_stack([(points[:, 0] - ax[1]) / ax[0], (points[:, 1] - ay[1]) / ay[0]])
