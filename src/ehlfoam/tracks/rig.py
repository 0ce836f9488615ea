"""The oil on the rig's tracks between passes of the contact: the disc's track, the ball's,
what the contact takes from them and lays back, and their reflow over a revolution. SI units;
volumes of the half width y >= 0 (the contact's half domain) unless said otherwise.

The rig turns the disc's track (radius r) and the ball (radius R) through the contact at the
rolling speed u; no oil is added. Each wall carries a layer across its track, h(y), uniform
along it. The contact takes in the layers on its rows (:class:`~ehlfoam.thinfilm.problem.
ThinFilmProblem`'s ``supply_layers``) and lays back, row by row, what leaves its outlet
(:attr:`~ehlfoam.thinfilm.march.Marcher.oil_out_rows`): the walls leave it at the same speed,
so the films are laid on both equally in pure rolling (``disc_share`` = 1/2), the oil that
leaves through the domain's side on its last row. Between a layer's laying and its return to
the inlet it levels for a revolution (:func:`~ehlfoam.tracks.reflow.reflow`): 2 pi r / u on
the disc, 2 pi R / u on the ball.

**The ball's more frequent passes.** The ball goes round r / R times a disc revolution (4.1
on the reference rig). A pass of the contact is a ball revolution: the disc's track is cut
into K = round(r / R) arcs, one taken in and laid back each pass, each met again K passes
later; the ball's track is taken in and laid back every pass. A pass lasts a K-th of the
disc's revolution, a whole number of the contact's steps (the arcs' length u times it), so
the oil the contact takes in is the arc's exactly and the rig's oil is kept to round-off.
The ball's layer levels for its own revolution 2 pi R / u; its track is counted one arc long
(2 pi r / K, 2.3 % longer than 2 pi R on the reference rig, r = 39 mm, R = 9.525 mm).
Each arc holds one profile: what was laid on it, averaged along it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ehlfoam._io import atomic_write
from ehlfoam.thinfilm.solution import ThinFilmSolution
from ehlfoam.tracks.reflow import reflow

__all__ = ["Rig", "Tracks", "equivalent_band", "outlet_layers"]


@dataclass(frozen=True)
class Rig:
    """The rig the contact runs on and how its tracks are modelled.

    Attributes:
        track_radius: r, the disc track's radius [m].
        ball_radius: R [m].
        speed: u [m/s].
        surface_tension: [N/m].
        viscosity: the oil's, at ambient pressure [Pa s].
        row: the contact grid's row width (its cell) [m].
        rows: the contact grid's rows (y from 0 to y_max).
        width_rows: the tracks' rows, the reflow's lateral domain (>= ``rows``).
        step: the contact's time step [s].
        refine: the reflow's cells per row.
        precursor: the reflow's precursor film [m] (mobility only, no oil).
        reflow_steps: backward Euler steps a revolution's reflow.
        centrifugal: the disc's layer feels rho u^2 / r outward (across the track) too;
            it is levelled on the full width and folded back onto y >= 0.
        density: the oil's [kg/m3] (the centrifugal force only).
        disc_share: the share of the contact's outflow laid on the disc (1/2 in pure
            rolling).
    """

    track_radius: float
    ball_radius: float
    speed: float
    surface_tension: float
    viscosity: float
    row: float
    rows: int
    width_rows: int
    step: float
    refine: int = 2
    precursor: float = 1e-9
    reflow_steps: int = 40
    centrifugal: bool = False
    density: float = 870.0
    disc_share: float = 0.5

    def __post_init__(self) -> None:
        checks = {
            "track_radius": (self.track_radius, self.track_radius > 0, "> 0 m"),
            "ball_radius": (self.ball_radius, self.ball_radius > 0, "> 0 m"),
            "speed": (self.speed, self.speed > 0, "> 0 m/s"),
            "row": (self.row, self.row > 0, "> 0 m"),
            "rows": (self.rows, self.rows >= 1, ">= 1"),
            "width_rows": (self.width_rows, self.width_rows >= max(self.rows, 3),
                           f">= {max(self.rows, 3)} (the contact's rows)"),
            "step": (self.step, self.step > 0, "> 0 s"),
            "refine": (self.refine, self.refine >= 1, ">= 1"),
            "disc_share": (self.disc_share, 0 <= self.disc_share <= 1, "in [0, 1]"),
        }
        for name, (value, ok, valid) in checks.items():
            if not ok:
                raise ValueError(f"{name} = {value!r} is out of range: must be {valid}")

    @property
    def arcs(self) -> int:
        """K: the disc track's arcs, a ball revolution each (round(r / R), at least 1)."""
        return max(1, round(self.track_radius / self.ball_radius))

    @property
    def pass_steps(self) -> int:
        """The contact's steps a pass: a K-th of the disc's revolution, rounded."""
        return max(1, round(2 * math.pi * self.track_radius
                            / (self.arcs * self.speed * self.step)))

    @property
    def pass_time(self) -> float:
        """A pass [s]: :attr:`pass_steps` steps."""
        return self.pass_steps * self.step

    @property
    def arc_length(self) -> float:
        """The length of track a pass takes in and lays back [m]: u times a pass."""
        return self.speed * self.pass_time

    @property
    def disc_revolution(self) -> float:
        """The time an arc of the disc's track levels between passes [s]: K passes."""
        return self.arcs * self.pass_time

    @property
    def ball_revolution(self) -> float:
        """The time the ball's layer levels between passes [s]: 2 pi R / u."""
        return 2 * math.pi * self.ball_radius / self.speed

    @property
    def y(self) -> np.ndarray:
        """The tracks' row centres [m]."""
        return self.row * (np.arange(self.width_rows) + 0.5)

    def level(self, layer: np.ndarray, duration: float, disc: bool) -> np.ndarray:
        """``layer`` on the tracks' rows after ``duration`` [s] of reflow, on ``refine``
        cells a row; on the full width (folded back) with the disc's centrifugal force."""
        fine = np.repeat(layer, self.refine)
        dy = self.row / self.refine
        force = self.density * self.speed**2 / self.track_radius \
            if disc and self.centrifugal else 0.0
        if force:
            fine = np.concatenate([fine[::-1], fine])
        out = reflow(fine, dy, duration, self.surface_tension, self.viscosity,
                     precursor=self.precursor, body_force=force,
                     steps=self.reflow_steps).h
        if force:
            half = out.size // 2
            out = 0.5 * (out[half:] + out[:half][::-1])
        return out.reshape(-1, self.refine).mean(axis=1)


@dataclass
class Tracks:
    """The layers on the tracks [m]: the disc's K arcs (K, width_rows), the ball's
    (width_rows,), the arc the contact meets next and the passes made."""

    disc: np.ndarray
    ball: np.ndarray
    next_arc: int = 0
    passes: int = 0

    @classmethod
    def uniform(cls, rig: Rig, disc_layer: float, ball_layer: float,
                half_width: float) -> "Tracks":
        """Uniform layers [m] on |y| < ``half_width`` [m] of both tracks (a row the edge
        cuts holds its share)."""
        d = rig.row
        on = np.clip((half_width - (rig.y - d / 2)) / d, 0.0, 1.0)
        return cls(disc=np.tile(disc_layer * on, (rig.arcs, 1)), ball=ball_layer * on)

    def inlet(self, rig: Rig) -> tuple[np.ndarray, np.ndarray]:
        """The layers (disc, ball) [m] that reach the contact's rows this pass."""
        return self.disc[self.next_arc, :rig.rows].copy(), self.ball[:rig.rows].copy()

    def oil(self, rig: Rig) -> tuple[float, float]:
        """The oil on the disc's track and on the ball's [m3, half width]."""
        area = rig.arc_length * rig.row
        return float(self.disc.sum()) * area, float(self.ball.sum()) * area

    def lay(self, rig: Rig, outlet_rows: np.ndarray, side: float) -> None:
        """The pass is over: the contact took in the layers on its rows of the arc and the
        ball, and lays back what left its outlet on each row [m3] and its side [m3, on its
        last row], ``disc_share`` of it on the disc; both then level for their
        revolutions, and the next arc comes round. A row with a net inflow through the
        outlet (below zero: round-off, or oil the region drew in there) takes it from the
        other rows in proportion, the volume kept; ValueError if the contact drew in more
        than it let out (a region at the domain's edge)."""
        laid = np.asarray(outlet_rows, float).copy()
        laid[-1] += side
        if not laid.sum() >= 0:
            raise ValueError(f"the contact drew in {-laid.sum():.3g} m3 more through its "
                             "outlet and side than it let out: its region reaches the "
                             "domain's edge (widen the domain: domain.side, "
                             "domain.downstream)")
        if (laid < 0).any():                         # round-off, or oil drawn in there:
            pos = np.clip(laid, 0.0, None)           # from the other rows, volume kept
            laid = pos * (laid.sum() / pos.sum())
        layer = laid / (rig.arc_length * rig.row)
        disc, ball = self.disc[self.next_arc].copy(), self.ball.copy()
        disc[:rig.rows] = rig.disc_share * layer
        ball[:rig.rows] = (1.0 - rig.disc_share) * layer
        self.disc[self.next_arc] = rig.level(disc, rig.disc_revolution, disc=True)
        self.ball = rig.level(ball, rig.ball_revolution, disc=False)
        self.next_arc = (self.next_arc + 1) % rig.arcs
        self.passes += 1

    def save(self, path: str | Path) -> None:
        """Write the tracks to ``path`` (.npz), atomically."""
        atomic_write(Path(path), lambda fh: np.savez_compressed(
            fh, disc=self.disc, ball=self.ball, next_arc=np.int64(self.next_arc),
            passes=np.int64(self.passes)))

    @classmethod
    def load(cls, path: str | Path) -> "Tracks":
        with np.load(path) as d:
            return cls(disc=d["disc"], ball=d["ball"], next_arc=int(d["next_arc"]),
                       passes=int(d["passes"]))


def outlet_layers(sol: ThinFilmSolution, disc_share: float = 0.5
                  ) -> tuple[np.ndarray, np.ndarray]:
    """The layers (disc, ball) [m] a thin-film state ``sol`` leaves behind, row by row: the
    oil content of its last column, which the walls carry out at u, ``disc_share`` of it on
    the disc. At the state's balance u times their sum over the rows is the supply (half
    domain). Raises ValueError where the flooded region reaches the outlet: there the flux
    out is the small difference of the Couette and Poiseuille fluxes, which a state's cell
    gaps cannot give (a march's exact profile is
    :attr:`~ehlfoam.thinfilm.march.Marcher.oil_out_rows`)."""
    last = sol.flooded[:, -1]
    if last.any():
        raise ValueError(f"the flooded region reaches the outlet on {int(last.sum())} rows: "
                         "the layers it leaves are read from a march (Marcher.oil_out_rows), "
                         "not from its state (or move the outlet out: domain.downstream)")
    c = np.clip(sol.content[:, -1], 0.0, None)
    return disc_share * c, (1.0 - disc_share) * c


def equivalent_band(disc: np.ndarray, ball: np.ndarray, row: float, share: float = 0.01
                    ) -> dict[str, float]:
    """The uniform band that carries the oil of the layers ``disc``, ``ball`` [m] on the rows
    y = row (i + 1/2), i = 0, 1, ... (half width; row [m]): the 3D scenes' "layers" supply
    (dotted case-spec keys, SI). Its edges are where the oil of both walls together, summed
    from y = 0, reaches ``share`` (the inner edge of a dry middle, ``track_inner_half_width``,
    0 when the middle carries oil) and 1 - ``share`` (``track_half_width``), each to a row's
    edge; its layers hold each wall's oil over that width. ValueError without oil."""
    disc, ball = np.clip(np.asarray(disc, float), 0, None), np.clip(np.asarray(ball, float), 0, None)
    total = disc + ball
    if not total.sum() > 0:
        raise ValueError("the tracks carry no oil onto the contact's rows")
    cum = np.cumsum(total) / total.sum()
    inner = row * int(np.searchsorted(cum, share, side="right"))
    outer = row * (int(np.searchsorted(cum, 1.0 - share)) + 1)
    width = outer - inner
    return {"supply.disc_layer": float(disc.sum()) * row / width,
            "supply.ball_layer": float(ball.sum()) * row / width,
            "supply.track_half_width": outer, "supply.track_inner_half_width": inner}
