"""Stroke geometry and the time-indexed pen-tip reference of the calligraphy task.

Characters are lists of strokes; a stroke is a polyline in the character frame [cm] (u to the
writer's right, v up the page), arcs sampled every 5°. On the table the page's "up" is world
+x (away from the robot base) and "right" is world −y. ``build_reference`` turns a placed
character into a pen-tip reference sampled every ``DT_REF_S``: hover above the first stroke,
then per stroke descend, dwell, write at constant speed, lift, travel to the next stroke.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

DT_REF_S = 0.005
"""Sampling period of the reference [s]."""


def arc(center: tuple[float, float], radius: float, deg0: float, deg1: float) -> np.ndarray:
    """Circular arc from angle ``deg0`` to ``deg1`` [°] (either direction), points every ≤5°."""
    n = max(2, int(np.ceil(abs(deg1 - deg0) / 5.0)) + 1)
    a = np.deg2rad(np.linspace(deg0, deg1, n))
    return np.column_stack([center[0] + radius * np.cos(a), center[1] + radius * np.sin(a)])


def bowed(p0: tuple[float, float], p1: tuple[float, float], sagitta: float) -> np.ndarray:
    """Circular arc from ``p0`` to ``p1`` bulging by ``sagitta`` to the left of p0→p1 [cm]."""
    a, b = np.asarray(p0, float), np.asarray(p1, float)
    chord = b - a
    c = float(np.linalg.norm(chord))
    left = np.array([-chord[1], chord[0]]) / c
    radius = (c * c / 4.0 + sagitta * sagitta) / (2.0 * sagitta)
    center = (a + b) / 2.0 - (radius - sagitta) * left
    ang0 = np.degrees(np.arctan2(*(a - center)[::-1]))
    ang1 = np.degrees(np.arctan2(*(b - center)[::-1]))
    sweep = (ang1 - ang0 + 180.0) % 360.0 - 180.0  # the short way round (sagitta < radius)
    return arc(tuple(center), radius, ang0, ang0 + sweep)


def _line(*pts: tuple[float, float]) -> np.ndarray:
    return np.asarray(pts, dtype=float)


CHARACTERS: dict[str, list[np.ndarray]] = {
    "shi": [_line((-3, 0.5), (3, 0.5)), _line((0, 3), (0, -3))],  # 十
    "kou": [_line((-2.5, 2.5), (-2.5, -2.5)),  # 口
            _line((-2.5, 2.5), (2.5, 2.5), (2.5, -2.5)),
            _line((-2.5, -2.5), (2.5, -2.5))],
    "ren": [bowed((0, 3), (-3, -3), 0.8), bowed((0, 0.5), (3, -3), -0.5)],  # 人
    "da": [_line((-3, 1), (3, 1)), bowed((0, 3), (-3, -3), 0.8), _line((0, 1), (3, -3))],  # 大
    "gong": [_line((-2.5, 2.5), (2.5, 2.5)), _line((0, 2.5), (0, -2.5)),  # 工
             _line((-3, -2.5), (3, -2.5))],
    "circle": [arc((0, 0), 2.5, 90, 450)],  # 〇, one closed stroke, counter-clockwise
}
"""The character library [cm]: lines and arcs forming a few simple characters."""


def place_strokes(strokes: list[np.ndarray], center_xy: np.ndarray, rot_rad: float,
                  scale: float) -> list[np.ndarray]:
    """Character-frame strokes [cm] → world xy polylines [m] (page up = +x, right = −y)."""
    c, s = np.cos(rot_rad), np.sin(rot_rad)
    rot = np.array([[c, -s], [s, c]])
    out = []
    for stroke in strokes:
        uv = stroke * (0.01 * scale)
        xy = np.column_stack([uv[:, 1], -uv[:, 0]])  # u → −y, v → +x
        out.append(center_xy + xy @ rot.T)
    return out


@dataclass
class Reference:
    """Pen-tip reference [m, world] sampled every ``DT_REF_S``.

    Attributes:
        points: (N, 3) tip targets.
        stroke: (N,) index of the stroke being written, −1 while not writing.
        paths: world xy polylines of the strokes.
        t_end_s: time at which the last stroke is done and the pen is back at hover [s].
    """

    points: np.ndarray
    stroke: np.ndarray
    paths: list[np.ndarray]
    t_end_s: float

    def at(self, time_s: float) -> tuple[np.ndarray, int]:
        """Reference point and stroke index at ``time_s`` (held after the end)."""
        x = time_s / DT_REF_S
        i = int(x)
        if i >= len(self.points) - 1:
            return self.points[-1].copy(), -1
        w = x - i
        return (1.0 - w) * self.points[i] + w * self.points[i + 1], int(self.stroke[i])


def _resample(path_xyz: np.ndarray, speed: float, min_s: float = DT_REF_S) -> np.ndarray:
    """Points along a 3-D polyline at constant ``speed`` [m/s], one per ``DT_REF_S``."""
    seg = np.linalg.norm(np.diff(path_xyz, axis=0), axis=1)
    s = np.concatenate([[0.0], np.cumsum(seg)])
    n = max(2, int(np.ceil(max(s[-1] / speed, min_s) / DT_REF_S)) + 1)
    q = np.linspace(0.0, s[-1], n)
    return np.column_stack([np.interp(q, s, path_xyz[:, k]) for k in range(3)])


def build_reference(paths: list[np.ndarray], surface_z: float, *, hover_dz: float = 0.03,
                    ready_dz: float = 0.08, settle_s: float = 3.0, write_speed: float = 0.03,
                    descend_s: float = 0.6, dwell_s: float = 0.6, lift_s: float = 0.4,
                    travel_speed: float = 0.1, final_s: float = 0.5) -> Reference:
    """Time-indexed pen-tip reference for writing ``paths`` (world xy [m]) on ``surface_z``.

    The pen first waits ``settle_s`` at ``ready_dz`` above the first stroke (high enough that a
    heavy tool sagging under plain impedance stays off the paper while IMPACT learns its
    weight), then every stroke: descend at ``hover_dz / descend_s``, dwell, write at
    ``write_speed``, lift to ``hover_dz`` in ``lift_s``, travel at ``travel_speed``.
    Heights are above ``surface_z`` [m]; speeds [m/s]; durations [s].
    """
    chunks: list[np.ndarray] = []
    labels: list[np.ndarray] = []

    def add(points: np.ndarray, label: int) -> None:
        chunks.append(points)
        labels.append(np.full(len(points), label))

    def hold(p: np.ndarray, seconds: float) -> None:
        add(np.repeat(p[None], max(1, round(seconds / DT_REF_S)), axis=0), -1)

    def up(xy: np.ndarray, dz: float = hover_dz) -> np.ndarray:
        return np.array([xy[0], xy[1], surface_z + dz])

    def down(xy: np.ndarray) -> np.ndarray:
        return np.array([xy[0], xy[1], surface_z])

    hold(up(paths[0][0], ready_dz), settle_s)
    for k, path in enumerate(paths):
        start = up(path[0], ready_dz if k == 0 else hover_dz)
        add(_resample(np.stack([start, down(path[0])]), hover_dz / descend_s), -1)
        hold(down(path[0]), dwell_s)
        add(_resample(np.column_stack([path, np.full(len(path), surface_z)]), write_speed), k)
        add(_resample(np.stack([down(path[-1]), up(path[-1])]), hover_dz / lift_s), -1)
        if k + 1 < len(paths):
            add(_resample(np.stack([up(path[-1]), up(paths[k + 1][0])]), travel_speed, 0.3), -1)
    hold(up(paths[-1][-1]), final_s)
    points = np.concatenate(chunks)
    return Reference(points, np.concatenate(labels), paths, len(points) * DT_REF_S)


def distance_to_path(xy: np.ndarray, path: np.ndarray) -> float:
    """Shortest distance [m] from point ``xy`` to the polyline ``path`` (M, 2)."""
    a, b = path[:-1], path[1:]
    ab = b - a
    t = np.clip(np.einsum("ij,ij->i", xy - a, ab) / np.maximum(np.einsum("ij,ij->i", ab, ab),
                                                               1e-12), 0.0, 1.0)
    d = a + t[:, None] * ab - xy
    return float(np.sqrt(np.einsum("ij,ij->i", d, d).min()))


class WritingMetrics:
    """Running writing metrics over the samples taken while a stroke is being written.

    Args:
        force_band_n: (low, high) normal force counted as "in band" [N].
        contact_min_n: below this normal force the pen is off the paper [N].
        gap_max_s: a contact gap longer than this is a loss of contact [s].
    """

    def __init__(self, force_band_n: tuple[float, float], contact_min_n: float,
                 gap_max_s: float) -> None:
        self.band = force_band_n
        self.contact_min_n = contact_min_n
        self.gap_max_s = gap_max_s
        self.reset()

    def reset(self) -> None:
        """Forget all samples."""
        self.n = self.n_in_band = 0
        self.sq_dist = self.gap_s = 0.0
        self.contact_lost = False

    def in_band(self, force_n: float) -> bool:
        """Whether a normal force [N] lies in the band."""
        return self.band[0] <= force_n <= self.band[1]

    def add(self, force_n: float, dist_m: float, dt_s: float) -> None:
        """One sample: normal force [N], distance of the tip from the stroke [m], period [s]."""
        self.n += 1
        self.n_in_band += int(self.in_band(force_n))
        self.sq_dist += dist_m * dist_m
        self.gap_s = self.gap_s + dt_s if force_n < self.contact_min_n else 0.0
        self.contact_lost |= self.gap_s > self.gap_max_s

    def end_stroke(self) -> None:
        """A stroke ended: the pen may leave the paper."""
        self.gap_s = 0.0

    def summary(self) -> dict[str, float | bool]:
        """``stroke_rms_m`` [m], ``in_band_frac``, ``contact_lost`` (0 / 0 / False if empty)."""
        n = max(self.n, 1)
        return {"stroke_rms_m": float(np.sqrt(self.sq_dist / n)),
                "in_band_frac": self.n_in_band / n,
                "contact_lost": bool(self.contact_lost)}
