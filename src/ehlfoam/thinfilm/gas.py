"""The gas of the thin-film model's cavities as a physical balance (``bubble_gas =
"balance"``): each cavity (the open cells the flooded region encloses,
:mod:`ehlfoam.thinfilm.cavity`) holds an amount of air n [mol]; its pressure is the ideal
gas's, p = n R T / V, over its volume V = sum of (h - c) d^2 (the gap less the oil its cells
hold), and the oil meets it in menisci at Young-Laplace's pressure below it, as it meets the
outer air at ambient. SI units throughout; amounts, volumes and rates over the half domain the
model marches.

Where the gas comes from and where it goes (:class:`CavityGas`):

- **Diffusion across the cavity's menisci.** The oil is saturated with air at ambient
  (Henry's law with the Ostwald coefficient s: C = s p / (R T) [mol/m3] at a partial
  pressure p), its concentration C0 = s p_atm / (R T) wherever it has not met a cavity; the
  interface holds C(p). Across the meniscus area A (a half circle across the gap on every face
  between a cavity cell and a flooded one: pi h / 2 times the face) the oil sliding past for
  the cavity's length l at u exchanges k_L A (C0 - C(p)) [mol/s], with Higbie's penetration
  coefficient k_L = 2 sqrt(D / (pi t)), t = l / u.
- **The films the walls carry through it.** The oil of a cavity's cells (its film content c,
  c / 2 on each wall) meets the gas on one side for the same t; a slab's diffusion gives the
  share f(D t / (c/2)^2) of its excess it gives up (all of it for films of a micrometre at
  these speeds), over the oil flux Q the walls carry out of the cavity at its rear.

  Both together: dn/dt = s (k_L A + f Q) (p_atm - p) / (R T), release where the gas is below
  the oil's saturation pressure, dissolution where it is above it (a compressed cavity): the
  oil's dissolved air is the only source and sink while the cavity is enclosed. Integrated
  exactly over a step at fixed V (a relaxation of n to p_atm V / (R T)), so it is stable at
  any rate.
- **Below the release pressure.** The gas is never below the release (nucleation) pressure
  p_r (physics.cavitation_pressure): a cavity opens where the oil would fall below it with
  its gas at p_r, and where the walls open a cavity's volume faster than the diffusion fills
  it, gas comes out of the oil at once to hold p_r (``released_at_release_pressure``).
- **Out of the domain.** A cavity that reaches the outer air gives it its gas
  (``escaped``: state II); one that closes (its cells flood) dissolves it
  (``dissolved_on_collapse``).

The budget (:attr:`CavityGas.budget`) closes: what the cavities hold changed by what was
released less what dissolved and escaped, to round-off. The vapour of the oil (a mineral oil's
is below 10 Pa at 60 C, 1e-4 of the gas's) is left out. docs/models/thin-film.md#the-outlet
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy import ndimage

__all__ = ["GAS_CONSTANT", "CavityGas", "GasBalance", "film_share", "penetration_coefficient"]

#: the molar gas constant [J/(mol K)]
GAS_CONSTANT = 8.314462618

_FOUR = ndimage.generate_binary_structure(2, 1)


@dataclass(frozen=True)
class GasBalance:
    """The constants of the gas balance, SI.

    Attributes:
        solubility: the Ostwald coefficient s of air in the oil [-]: volumes of gas (at its
            own pressure and temperature) a volume of saturated oil holds; C = s p / (R T).
        diffusivity: of air in the oil [m2/s], at the case's temperature and viscosity.
        temperature: of the oil and its gas [K].
        ambient: the outer air's pressure [Pa, absolute]; the oil is saturated at it.
        release: the release (nucleation) pressure p_r [Pa, absolute]: below it the oil
            gives up gas at once.
    """

    solubility: float
    diffusivity: float
    temperature: float
    ambient: float
    release: float

    def __post_init__(self) -> None:
        checks = {"solubility": (self.solubility, 0 <= self.solubility <= 1, "in [0, 1]"),
                  "diffusivity": (self.diffusivity, 0 < self.diffusivity < 1e-5,
                                  "in (0, 1e-5) m2/s"),
                  "temperature": (self.temperature, 200 < self.temperature < 500,
                                  "in (200, 500) K"),
                  "ambient": (self.ambient, self.ambient > 0, "> 0 Pa"),
                  "release": (self.release, 0 < self.release < self.ambient,
                              f"in (0, {self.ambient:g}) Pa: below the ambient pressure")}
        for name, (value, ok, valid) in checks.items():
            if not ok:
                raise ValueError(f"{name} = {value!r} is out of range: must be {valid}")

    @property
    def rt(self) -> float:
        """R T [J/mol]."""
        return GAS_CONSTANT * self.temperature


def penetration_coefficient(diffusivity: float, time: float) -> float:
    """Higbie's mass-transfer coefficient [m/s] of an interface that fresh liquid slides past
    for ``time`` [s]: 2 sqrt(D / (pi t))."""
    return 2.0 * np.sqrt(diffusivity / (np.pi * time)) if time > 0 else 0.0


def film_share(fourier: float) -> float:
    """The share of its excess of dissolved gas that a film on a wall gives up through its
    free surface in the time t, at Fourier number D t / delta^2 (delta its thickness; the
    wall impermeable): 1 - sum 8 / ((2n+1)^2 pi^2) exp(-(2n+1)^2 pi^2 Fo / 4)."""
    if fourier <= 0:
        return 0.0
    n = 2 * np.arange(60) + 1
    return float(np.clip(1.0 - np.sum(8.0 / (n * np.pi) ** 2
                                      * np.exp(-(n * np.pi) ** 2 * fourier / 4.0)), 0.0, 1.0))


class CavityGas:
    """The air every cavity of a march holds, as an amount per cell [mol] (a cavity's amount
    spread over its cells by their volume, so that it follows the cells as the cavity moves,
    splits and merges), and the budget of what it exchanged.

    ``h``: the gap at the cells (0 in the island) [m]; ``hx``, ``hy``: at the x and y faces
    [m]; ``cell`` [m]; ``speed`` u [m/s] (:attr:`u`, which a march with a stop changes
    between steps: at rest the exchange with oil sliding past stops)."""

    def __init__(self, constants: GasBalance, h: np.ndarray, hx: np.ndarray, hy: np.ndarray,
                 cell: float, speed: float):
        self.k = constants
        self.h, self.hx, self.hy = h, np.nan_to_num(hx), np.nan_to_num(hy)
        self.d, self.u = cell, speed
        self.n = np.zeros_like(h)
        self.start = 0.0    # the air held when the budget began [mol]
        self.budget = {"released_by_diffusion_mol": 0.0,
                       "released_at_release_pressure_mol": 0.0,
                       "dissolved_by_diffusion_mol": 0.0, "dissolved_on_collapse_mol": 0.0,
                       "escaped_to_air_mol": 0.0}
        self.last: dict[str, float] = {}

    def held(self) -> float:
        """The air the cavities hold now [mol]."""
        return float(self.n.sum())

    def budget_residual(self) -> float:
        """What the cavities hold less what the budget says they should [mol]."""
        b = self.budget
        return self.held() - self.start - (b["released_by_diffusion_mol"]
                              + b["released_at_release_pressure_mol"]
                              - b["dissolved_by_diffusion_mol"] - b["dissolved_on_collapse_mol"]
                              - b["escaped_to_air_mol"])

    def _volumes(self, c: np.ndarray) -> np.ndarray:
        return np.clip(self.h - c, 0.0, None) * self.d * self.d

    def pressure(self, cavity: np.ndarray, c: np.ndarray) -> np.ndarray:
        """Every cavity cell's gas pressure [Pa, absolute] (NaN elsewhere): its cavity's
        n R T / V, not below the release pressure (a cavity of no volume yet is at it)."""
        labels, count = ndimage.label(cavity, structure=_FOUR)
        out = np.full(cavity.shape, np.nan)
        if count == 0:
            return out
        idx = np.arange(1, count + 1)
        n = ndimage.sum_labels(self.n, labels, idx)
        v = ndimage.sum_labels(self._volumes(c), labels, idx)
        p = np.where(v > 0, n * self.k.rt / np.where(v > 0, v, 1.0), 0.0)
        p = np.maximum(p, self.k.release)
        out[cavity] = p[labels[cavity] - 1]
        return out

    def advance(self, cavity: np.ndarray, c_old: np.ndarray, new_cavity: np.ndarray,
                outer: np.ndarray, c_new: np.ndarray, flooded_old: np.ndarray,
                dt: float) -> None:
        """One step: the exchange of every cavity of the step (``cavity``, the oil
        ``c_old`` in it, ``flooded_old`` the region around it) over ``dt`` [s], then its air
        handed on to the cavities after the step (``new_cavity``, oil ``c_new``) by the
        volume they share with it, or to the outer air (``outer``) where it reaches it."""
        k, b = self.k, self.budget
        labels, count = ndimage.label(cavity, structure=_FOUR)
        # a cavity cell of the step before that is not one now joined the outer air within
        # the step (its flooded cells only open): its gas went with it
        b["escaped_to_air_mol"] += float(self.n[~cavity].sum())
        self.n = np.where(cavity, self.n, 0.0)
        if count == 0:
            self.last = {}
            return
        idx = np.arange(1, count + 1)
        v_old = self._volumes(c_old)
        V = ndimage.sum_labels(v_old, labels, idx)
        n = ndimage.sum_labels(self.n, labels, idx)
        floor = k.release * V / k.rt                    # the gas at the release pressure
        b["released_at_release_pressure_mol"] += float(np.sum(np.clip(floor - n, 0.0, None)))
        n = np.maximum(n, floor)
        rate = self._rate(labels, idx, cavity, c_old, flooded_old)   # [mol/(s Pa)]
        lam = np.where(V > 0, rate * k.rt / np.where(V > 0, V, 1.0), 0.0)
        n_eq = k.ambient * V / k.rt
        n_new = n_eq + (n - n_eq) * np.exp(-lam * dt)
        gain = n_new - n
        b["released_by_diffusion_mol"] += float(np.sum(np.clip(gain, 0.0, None)))
        b["dissolved_by_diffusion_mol"] += float(np.sum(np.clip(-gain, 0.0, None)))
        biggest = int(np.argmax(V))
        self.last = {"pressure_Pa": float(n_new[biggest] * k.rt / V[biggest])
                     if V[biggest] > 0 else k.release,
                     "volume_m3": float(V[biggest]), "rate_mol_s": float(gain[biggest] / dt)}
        self._hand_on(labels, idx, n_new, new_cavity, outer, c_new)

    def _rate(self, labels, idx, cavity, c, flooded) -> np.ndarray:
        """Every cavity's exchange coefficient s (k_L A + f Q) / (R T) [mol/(s Pa)]."""
        k, d, u = self.k, self.d, self.u
        cols = np.nonzero(cavity.any(axis=0))[0]
        x_index = np.broadcast_to(np.arange(cavity.shape[1]), cavity.shape)
        first = ndimage.minimum(x_index, labels, idx)
        last = ndimage.maximum(x_index, labels, idx)
        length = (np.asarray(last) - np.asarray(first) + 1.0) * d if cols.size else 0.0
        # the oil's time along the cavity; at rest (walls stopped) no oil slides past it
        t = length / u if u > 0 else np.full(np.shape(length), np.inf)
        # meniscus area: pi h / 2 on every face between a cavity cell and a flooded one
        area = np.zeros(cavity.shape)
        for axis, hf in ((1, self.hx), (0, self.hy)):
            lo = [slice(None)] * 2
            hi = [slice(None)] * 2
            lo[axis], hi[axis] = slice(None, -1), slice(1, None)
            a = 0.5 * np.pi * hf * d
            cav_lo = cavity[tuple(lo)] & flooded[tuple(hi)]
            cav_hi = cavity[tuple(hi)] & flooded[tuple(lo)]
            area[tuple(lo)] += np.where(cav_lo, a, 0.0)
            area[tuple(hi)] += np.where(cav_hi, a, 0.0)
        A = ndimage.sum_labels(area, labels, idx)
        # the films: the oil the walls carry out of a cavity cell into a cell not its own
        leaves = np.zeros(cavity.shape, bool)
        leaves[:, :-1] = cavity[:, :-1] & ~cavity[:, 1:] & (self.hx > 0)
        q = np.where(leaves, u * c * d, 0.0)
        Q = ndimage.sum_labels(q, labels, idx)
        faces = ndimage.sum_labels(leaves.astype(float), labels, idx)
        film = ndimage.sum_labels(np.where(leaves, c, 0.0), labels, idx)
        delta = np.where(faces > 0, film / np.maximum(faces, 1.0) / 2.0, 0.0)
        kl = np.array([penetration_coefficient(k.diffusivity, ti) for ti in np.atleast_1d(t)])
        f = np.array([film_share(k.diffusivity * ti / dl**2) if dl > 0 else 0.0
                      for ti, dl in zip(np.atleast_1d(t), delta)])
        return k.solubility * (kl * A + f * Q) / k.rt

    def _hand_on(self, labels, idx, n, new_cavity, outer, c_new) -> None:
        """Each old cavity's air to the new cavities and the outer air by the volume of its
        cells they hold now; a cavity none of whose cells is open now has closed."""
        b = self.budget
        v = self._volumes(c_new) + 1e-30 * self.d ** 2   # a just-opened cell counts a little
        new_labels, new_count = ndimage.label(new_cavity, structure=_FOUR)
        gets = np.zeros(new_count + 1)
        old = labels.ravel()
        for j, nk in zip(idx, n):
            cells = old == j
            nl = new_labels.ravel()[cells]
            w = v.ravel()[cells]
            w_air = float(w[outer.ravel()[cells]].sum())
            w_cav = np.bincount(nl, weights=w * (nl > 0), minlength=new_count + 1)
            total = w_air + float(w_cav.sum())
            if total <= 0 or (w_air == 0 and not w_cav[1:].any()):
                b["dissolved_on_collapse_mol"] += float(nk)
                continue
            b["escaped_to_air_mol"] += float(nk) * w_air / total
            gets += float(nk) * w_cav / total
        V_new = ndimage.sum_labels(v, new_labels, np.arange(1, new_count + 1))
        share = np.zeros_like(self.n)
        if new_count:
            per = np.where(V_new > 0, gets[1:] / V_new, 0.0)
            share[new_cavity] = per[new_labels[new_cavity] - 1] * v[new_cavity]
        self.n = share
