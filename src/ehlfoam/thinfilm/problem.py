"""One thin-film problem (:class:`ThinFilmProblem`: the gap, the walls' speed, the oil, the
wetting, the supply and the grid's cell) and its grid of square cells (:class:`Grid`), SI
units. The model itself: :mod:`ehlfoam.thinfilm.march`."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Literal

import numpy as np

from ehlfoam.thinfilm.gas import GasBalance

#: A row whose supply layers are below this share of the profile's largest counts as dry
#: walls coming in (the advancing angle applies there).
DRY_SHARE = 0.01


def landau_levich(eta: float, u: float, sigma: float) -> float:
    """Both walls' films over the gap [-] behind a meniscus receding at u between two walls
    (r = h / 2; Aussillous and Quere's fit of Landau-Levich)."""
    c = (eta * u / sigma) ** (2.0 / 3.0)
    return 2.0 * 1.34 * c * 0.5 / (1.0 + 3.35 * c)


@dataclass(frozen=True)
class ThinFilmProblem:
    """One thin-film problem, SI units.

    Attributes:
        gap: h(x, y) [m] for arrays x, y [m] (contact centre at the origin, rolling along +x).
        speed: u of both walls [m/s] (0: at rest, the problem of a march's step after a
            stop; a march itself starts at u > 0).
        viscosity: oil viscosity [Pa s].
        surface_tension: [N/m].
        contact_angle: static contact angle of the oil on both walls [deg].
        supply: oil carried in on the track, both walls together [m].
        track_half_width: half-width of the track [m].
        x_range: the domain along x [m]; it spans 0 <= y <= y_max [m].
        island_radius: the contact's island, no flow inside it [m].
        cell: cell size [m].
        initial_radius: radius of the flooded puddle at t = 0 [m].
        film_factor: multiplies Landau-Levich's films (1: the model).
        closed_side: the side y = y_max is a symmetry plane too, not open to the air (a
            strip of a problem that does not vary along y).
        receding_meniscus: the capillary pressure of a meniscus that the walls leave
            (at the region's rear): "static", Young-Laplace's
            -2 sigma cos(theta) / h like every other; "bretherton", that of a meniscus laying
            films (Park and Homsy 1984, Hele-Shaw): -(2 sigma / h) (1 + 3.8 Ca^(2/3)), with
            no contact angle (the walls behind it are wet), at the rear where the walls leave
            it square on; at Ca = 0.006 that draws 16 % harder than the static one. A number
            in [0.5, 2]: that factor on the static pressure there (to measure how much the
            region hangs on it). Either way the factor falls off as n^(2/3) where the walls
            leave the meniscus at an angle (n the x part of its outward normal; the films'
            Ca n) and is 1 where they run along it or into it.
        normal_length: the length [m] over which the flooded cells are smoothed (Gaussian
            standard deviation) for that normal; None: 1.5 cells. A length fixed in metres
            keeps the normal, and so the pull, the same on every grid; 1.5 cells of 0.1 a
            let single cells flipping at the meniscus swing n, and n^(2/3) is steep at small
            n, by pressures the size of those that shape the region (tens of Pa): the rear
            meniscus drained within a step and shed its oil in streaks.
        advancing_angle: the apparent contact angle [deg] of a meniscus the walls advance
            into from dry ground (off the track, where no supply layer meets it), where they
            meet it square on; None: the static angle. Cox-Voinov's theta^3 - theta_s^3 grows
            with the capillary number of the contact line's speed, so at an angle theta^3
            takes the share n of the step from theta_s^3 (n: the x part of the meniscus's
            inward normal, from the region smoothed over ``normal_length``). In a strip of
            interFoam with dry walls advancing at the nominal Ca = 0.0058 the meniscus
            settles at 44-51 deg on in-plane cells within some 15 wall cells, and holds no
            suction at all on coarser ones (:mod:`ehlfoam.case.strip`).
        meniscus_position: where a meniscus sits in the open cell beside a flooded one:
            "sub-cell", as far into it as the cell's bulk oil fills it (its oil beyond the
            layers or films the walls carry, over the rest of its gap), so that the
            meniscus, its pressure (at the gap there) and the flooded cell's conductance to
            it move smoothly as the cell fills; "cell", at the cell's centre, so that they
            jump a cell at a time as cells flood and open (the first version: its balance
            moved by 6-16 % at each halving of the step).
        cavitation_pressure: the gauge pressure [Pa, < 0] below which the oil gives up gas
            (the gas-release pressure less the ambient one); None: the oil holds any
            tension (no outlet model). With it, a flooded cell whose pressure would fall
            below it opens to gas, the gas the flooded region encloses is at it, and a
            meniscus's pressure never falls below it (:mod:`ehlfoam.thinfilm.cavity`).
        gas: with a cavitation pressure, the cavities' gas as a balance (its constants,
            :class:`~ehlfoam.thinfilm.gas.GasBalance`): each cavity's pressure from the air
            it holds, released from and dissolved into the oil at the rates of diffusion,
            its menisci at Young-Laplace's pressure below it; the cavitation pressure is
            then the release pressure, below which the oil gives up gas at once. None: the
            cavities at the cavitation pressure.
    """

    gap: Callable[[np.ndarray, np.ndarray], np.ndarray]
    speed: float
    viscosity: float
    surface_tension: float
    contact_angle: float
    supply: float
    track_half_width: float
    x_range: tuple[float, float]
    y_max: float
    island_radius: float
    cell: float
    initial_radius: float
    film_factor: float = 1.0
    closed_side: bool = False
    receding_meniscus: Literal["static", "bretherton"] | float = "static"
    normal_length: float | None = None
    advancing_angle: float | None = None
    meniscus_position: Literal["sub-cell", "cell"] = "sub-cell"
    cavitation_pressure: float | None = None
    supply_layers: tuple[np.ndarray, np.ndarray] | None = field(default=None, compare=False)
    gas: GasBalance | None = None

    def __post_init__(self) -> None:
        span = min(self.y_max / 2, (self.x_range[1] - self.x_range[0]) / 8)
        checks = {
            "speed": (self.speed, self.speed >= 0, ">= 0 m/s (0: the walls at rest)"),
            "viscosity": (self.viscosity, self.viscosity > 0, "> 0 Pa s"),
            "surface_tension": (self.surface_tension, self.surface_tension > 0, "> 0 N/m"),
            "contact_angle": (self.contact_angle, 0 <= self.contact_angle < 90,
                              "in [0, 90) deg"),
            "supply": (self.supply, self.supply >= 0, ">= 0 m"),
            "track_half_width": (self.track_half_width, self.track_half_width > 0, "> 0 m"),
            "island_radius": (self.island_radius, self.island_radius >= 0, ">= 0 m"),
            "x_range": (self.x_range, self.x_range[0] < -self.island_radius
                        and self.x_range[1] > self.island_radius, "around the island"),
            "y_max": (self.y_max, self.y_max > self.island_radius, "beyond the island"),
            "cell": (self.cell, 0 < self.cell <= span, f"in (0, {span:.3g}] m: two cells "
                                                      "across, eight along the domain"),
            "film_factor": (self.film_factor, self.film_factor > 0, "> 0"),
            "receding_meniscus": (self.receding_meniscus,
                                  self.receding_meniscus in ("static", "bretherton")
                                  or (isinstance(self.receding_meniscus, (int, float))
                                      and not isinstance(self.receding_meniscus, bool)
                                      and 0.5 <= self.receding_meniscus <= 2.0),
                                  "'static', 'bretherton' or a factor in [0.5, 2]"),
            "advancing_angle": (self.advancing_angle, self.advancing_angle is None
                                or self.contact_angle <= self.advancing_angle < 90,
                                f"None or in [{self.contact_angle:g}, 90) deg: the static "
                                "angle up to a right angle"),
            "normal_length": (self.normal_length, self.normal_length is None
                              or 0.5 * self.cell <= self.normal_length <= span,
                              f"None or in [{0.5 * self.cell:.3g}, {span:.3g}] m: half a "
                              "cell to the span of the cell's check"),
            "cavitation_pressure": (self.cavitation_pressure, self.cavitation_pressure is None
                                    or (np.isfinite(self.cavitation_pressure)
                                        and self.cavitation_pressure < 0),
                                    "None or a finite gauge pressure < 0 Pa (below ambient)"),
            "gas": (self.gas, self.gas is None or self.cavitation_pressure is not None,
                    "None without a cavitation_pressure (the balance is the cavities' gas)"),
        }
        for name, (value, ok, valid) in checks.items():
            if not ok:
                raise ValueError(f"{name} = {value!r} is out of range: must be {valid}")
        if self.supply_layers is not None:
            self._check_layers()

    @property
    def rows(self) -> int:
        """The grid's rows across y (:class:`Grid`)."""
        return int(round(self.y_max / self.cell))

    def _check_layers(self) -> None:
        ny = self.rows
        if len(self.supply_layers) != 2:
            raise ValueError(f"supply_layers has {len(self.supply_layers)} profiles: must be "
                             "(disc, ball)")
        for name, layer in zip(("disc", "ball"), self.supply_layers):
            layer = np.asarray(layer)
            if layer.shape != (ny,):
                raise ValueError(f"supply_layers ({name}) has shape {layer.shape}: must be "
                                 f"({ny},), a layer on each of the grid's rows")
            bad = ~(np.isfinite(layer) & (layer >= 0))
            if bad.any():
                raise ValueError(f"supply_layers ({name}) = {float(layer[bad][0]):g} m on row "
                                 f"{int(np.argmax(bad))} is out of range: must be finite "
                                 "and >= 0 m on every row")

    def supply_rows(self, y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The layers the walls bring in on the rows at ``y`` [m] (both walls together,
        [m]) and each row's share of wet wall (0-1; off the track 0): the profiles of
        ``supply_layers``, or ``supply`` on the track."""
        if self.supply_layers is None:
            d = self.cell
            on_track = np.clip((self.track_half_width - (y - d / 2)) / d, 0.0, 1.0)
            return self.supply * on_track, on_track
        total = np.asarray(self.supply_layers[0], float) + np.asarray(self.supply_layers[1],
                                                                         float)
        top = float(total.max()) if total.size else 0.0
        return total, (total > DRY_SHARE * top).astype(float) if top > 0 else 0.0 * total

    @property
    def film(self) -> float:
        """Films a receding meniscus leaves on both walls, over the gap [-]."""
        return self.film_factor * landau_levich(self.viscosity, self.speed,
                                                self.surface_tension)


@dataclass
class Grid:
    """Cell centres x (nx,), y (ny,) [m], gaps at the cells and faces, the island."""

    x: np.ndarray
    y: np.ndarray
    h: np.ndarray        # (ny, nx), NaN in the island
    hx: np.ndarray       # (ny, nx - 1) on the x faces, NaN on the island's
    hy: np.ndarray       # (ny - 1, nx) on the y faces
    h_side: np.ndarray   # (nx,) on y = y_max
    island: np.ndarray   # (ny, nx) bool

    @property
    def cell(self) -> float:
        return float(self.x[1] - self.x[0])

    @staticmethod
    def layout(prob: ThinFilmProblem) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The grid's cell centres x (nx,), y (ny,) [m] and its island (ny, nx), without
        the gaps (which cost the far field's sum)."""
        d = prob.cell
        nx = int(round((prob.x_range[1] - prob.x_range[0]) / d))
        ny = int(round(prob.y_max / d))
        x = prob.x_range[0] + d * (np.arange(nx) + 0.5)
        y = d * (np.arange(ny) + 0.5)
        return x, y, np.hypot(*np.meshgrid(x, y)) < prob.island_radius

    @classmethod
    def build(cls, prob: ThinFilmProblem) -> "Grid":
        d = prob.cell
        x, y, island = cls.layout(prob)
        nx, ny = len(x), len(y)
        xf = prob.x_range[0] + d * np.arange(1, nx)
        yf = d * np.arange(1, ny)
        return cls(x=x, y=y, h=_gap(prob.gap, *np.meshgrid(x, y), island),
                   hx=_gap(prob.gap, *np.meshgrid(xf, y), island[:, 1:] | island[:, :-1]),
                   hy=_gap(prob.gap, *np.meshgrid(x, yf), island[1:] | island[:-1]),
                   h_side=_gap(prob.gap, x, np.full(nx, prob.y_max), np.zeros(nx, bool)),
                   island=island)


def _gap(gap, X, Y, solid) -> np.ndarray:
    out = np.full(np.shape(X), np.nan)
    ok = ~np.asarray(solid)
    out[ok] = gap(np.asarray(X)[ok], np.asarray(Y)[ok])
    return out
