"""Read what a running or finished case wrote: time folders, fields, samples of the flow.

The monitor calls :func:`sample` on every new time folder: the oil volume, the oil fluxes
through the open boundaries and the flow-pattern metrics of the mid-gap oil fraction.
Volumes and fluxes are for the whole contact (doubled in a half domain).
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from foamlib import FoamFieldFile
from scipy.spatial import cKDTree

from ehlfoam.case.dictionaries import AIR_GAS_CONSTANT
from ehlfoam.case.geometry import META, CaseGeometry
from ehlfoam.foam.fieldfile import field_file

from ehlfoam.metrics import pattern as metrics

SUPPLY_PATCH = "supply"
OPEN_PATCHES = (SUPPLY_PATCH, "inlet", "outlet", "side")


#: :func:`bare_track_share`: the part of the track's half width it reads (its edges, where the
#: layers end, excluded) and the oil below which a column counts as bare (of the layers)
BARE_TRACK_SPAN = 0.8
BARE_TRACK_OIL = 0.25


@dataclass
class Structure:
    """The mesh structure the generator stored in ``ehlfoam/mesh.npz``."""

    cell_volumes: np.ndarray
    base_cell: np.ndarray
    layer: np.ndarray
    base_x: np.ndarray
    base_y: np.ndarray
    patches: dict[str, tuple[int, int]]  # name -> (start among boundary faces, size)
    #: per base cell: the height of its cell on the disc [m] and its in-plane area [m2]
    wall_cell: np.ndarray | None = None
    footprint: np.ndarray | None = None

    @classmethod
    def load(cls, case: str | os.PathLike) -> "Structure":
        d = np.load(Path(case) / META / "mesh.npz")
        base = d["base_cell"]
        n_base = int(base.max()) + 1
        centres = d["cell_centres"]
        count = np.bincount(base, minlength=n_base)
        bx = np.bincount(base, centres[:, 0], minlength=n_base) / count
        by = np.bincount(base, centres[:, 1], minlength=n_base) / count
        patches = {str(n): (int(s), int(z)) for n, s, z in
                   zip(d["patch_names"], d["patch_starts"], d["patch_sizes"])}
        # the cell on the flat disc (z = 0) spans twice its centre's height
        on_disc = d["layer"] == 0
        wall = np.zeros(n_base)
        wall[base[on_disc]] = 2.0 * centres[on_disc, 2]
        area = np.zeros(n_base)
        area[base[on_disc]] = d["cell_volumes"][on_disc] / wall[base[on_disc]]
        return cls(d["cell_volumes"], base, d["layer"], bx, by, patches, wall, area)

    def column_gaps(self) -> np.ndarray:
        """Per base cell, the gap across its column [m]: the column's volume over its
        footprint."""
        return self._over_footprint(self.cell_volumes)

    def column_oil(self, alpha: np.ndarray) -> np.ndarray:
        """Per base cell, the oil across its column [m]: the oil's volume in it (``alpha``, the
        oil fraction per cell) over its footprint."""
        return self._over_footprint(np.asarray(alpha, float) * self.cell_volumes)

    def _over_footprint(self, volumes: np.ndarray) -> np.ndarray:
        """Per base cell, the sum of a per-cell volume [m3] over its column, over its
        footprint [m]."""
        return np.bincount(self.base_cell, volumes, minlength=len(self.base_x)) / self.footprint

    def gap_mean(self, field: np.ndarray) -> np.ndarray:
        """Per base cell, the volume-weighted mean of a cell field over the column across the
        gap (a scalar field gives shape (n_base,), a vector field (n_base, k))."""
        n_base = len(self.base_x)
        w = self.cell_volumes
        col = np.bincount(self.base_cell, w, minlength=n_base)
        f = np.asarray(field, float)
        if f.ndim == 1:
            return np.bincount(self.base_cell, f * w, minlength=n_base) / col
        return np.stack([np.bincount(self.base_cell, f[:, k] * w, minlength=n_base)
                         for k in range(f.shape[1])], axis=1) / col[:, None]

    def oil_column_speeds(self, U: np.ndarray, alpha: np.ndarray) -> np.ndarray:
        """Gap-averaged in-plane speed [m/s] of each column of cells that is oil
        (alpha > 0.99) from wall to wall: the net in-plane flow that can move a meniscus in
        a thin gap, without the recirculation across it (the static-meniscus measure)."""
        oil_column = self.gap_mean(np.asarray(alpha) <= 0.99) == 0.0
        return np.linalg.norm(self.gap_mean(np.asarray(U)[:, :2]), axis=1)[oil_column]

    def mid_gap(self, field: np.ndarray, n_layers: int) -> np.ndarray:
        """Per base cell, the value at mid-gap (the middle layer, or the mean of the two
        middle layers for an even count)."""
        mid = [n_layers // 2] if n_layers % 2 else [n_layers // 2 - 1, n_layers // 2]
        sel = np.isin(self.layer, mid)
        n_base = len(self.base_x)
        s = np.bincount(self.base_cell[sel], field[sel], minlength=n_base)
        c = np.bincount(self.base_cell[sel], minlength=n_base)
        return s / np.maximum(c, 1)


def time_folders(case: str | os.PathLike) -> list[tuple[float, Path]]:
    """Numeric time folders of the case (excluding 0), in time order."""
    out = []
    for p in Path(case).iterdir():
        if not p.is_dir():
            continue
        try:
            t = float(p.name)
        except ValueError:
            continue
        if t > 0.0 and math.isfinite(t):
            out.append((t, p))
    return sorted(out)


def write_near(case: str | os.PathLike, at: str, transit_time: float) -> tuple[float, Path]:
    """(time [s], folder) of the write nearest ``at`` transits (of ``transit_time`` s), or the
    last write for ``at = "last"``. Raises ValueError naming what is wrong."""
    times = time_folders(case)
    if not times:
        raise ValueError(f"{case} has no written time folders")
    if at == "last":
        return times[-1]
    try:
        transits = float(at)
    except ValueError:
        raise ValueError(f"time = {at!r} must be a number of transits or 'last'") from None
    return min(times, key=lambda tf: abs(tf[0] - transits * transit_time))


def uniform_or_list(value, n: int) -> np.ndarray:
    """A field's values as an array: a uniform value repeated ``n`` times, a list as it is."""
    arr = np.asarray(value, dtype=float)
    if arr.ndim == 0:
        return np.full(n, float(arr))
    return arr


@dataclass
class Sample:
    """The state of the flow at one written time (SI; lengths in metrics as ratios to a)."""

    time: float
    oil_volume: float       # m3, whole contact
    oil_in: float           # m3/s of oil entering through the open boundaries
    oil_out: float          # m3/s of oil leaving
    pattern: dict
    gas_mass: float | None = None   # kg of air, whole contact (compressible scenes only)
    gas_in: float | None = None     # kg/s of air entering through the open boundaries
    gas_out: float | None = None    # kg/s of air leaving
    oil_flux_exact: bool = True     # oil fluxes from the solver's alphaPhi0, not phi x alpha
    #: m3/s of oil leaving through each open boundary but the supply (outlet, side, inlet):
    #: oil leaving anywhere but the outlet means the flooded region or a film reached the edge
    oil_out_by_boundary: dict[str, float] = field(default_factory=dict)

    def row(self) -> dict:
        keys = ("state", "wake_open", "inlet_starved", "inlet_meniscus_distance_over_a",
                "inlet_meniscus_at_rim", "inlet_meniscus_shape", "inlet_meniscus_c2",
                "flooded_length_over_a", "flooded_width_over_a", "wake_gas_length_over_a",
                "enclosed_bubbles", "oil_smeared_fraction",
                "bubble_length_over_a", "bubble_volume_m3", "min_pressure_Pa",
                "gas_release_m3_s", "gas_dissolution_m3_s")
        gas = ({} if self.gas_mass is None else
               {"gas_mass_kg": self.gas_mass, "gas_in_kg_s": self.gas_in,
                "gas_out_kg_s": self.gas_out})
        by_boundary = {f"oil_out_{name}_m3_s": q for name, q in self.oil_out_by_boundary.items()}
        return {"time_s": self.time, "oil_volume_m3": self.oil_volume,
                "oil_in_m3_s": self.oil_in, "oil_out_m3_s": self.oil_out, **by_boundary,
                **{k: self.pattern.get(k) for k in keys}, **gas}


def pattern_geometry(geom: CaseGeometry) -> metrics.Geometry:
    return metrics.Geometry.of(geom.box, geom.a)


def _read_alpha(path: Path, structure: Structure) -> tuple[np.ndarray, FoamFieldFile]:
    """The oil fraction per cell of the alpha.oil file ``path`` (and the file, for its
    boundary values); IncompleteField (a ValueError) while OpenFOAM has not finished it."""
    n = len(structure.cell_volumes)
    file = field_file(path)
    alpha = uniform_or_list(file.internal_field, n)
    if alpha.shape != (n,):
        raise ValueError(f"{path} has {alpha.shape} values, expected {n}")
    return alpha, file


def _oil_volume(alpha: np.ndarray, structure: Structure, geom: CaseGeometry) -> float:
    """Oil volume [m3] of the whole contact (doubled in a half domain)."""
    return geom.mirror * float(np.sum(np.clip(alpha, 0.0, 1.0) * structure.cell_volumes))


#: Cells with an oil fraction between these bounds hold a smeared interface (not oil, not air).
SMEARED_ALPHA = (0.02, 0.98)


def smeared_oil_fraction(alpha: np.ndarray, cell_volumes: np.ndarray) -> float | None:
    """Share of the oil volume held in cells that are neither oil nor air
    (:data:`SMEARED_ALPHA`): how diffuse the interface is. A thin-gap meniscus is one or two
    cells wide in the plane, so a sharp run keeps a small, level-dependent share; the
    interface-limited compression scheme (``physics.interface_schemes = "balanced"``)
    raised it from 31 % to 44-48 % on the nominal case (docs/validation.md#v-balanced-rolling).
    None without oil."""
    a = np.clip(np.asarray(alpha, float), 0.0, 1.0)
    oil = a * np.asarray(cell_volumes, float)
    total = float(oil.sum())
    if total <= 0.0:
        return None
    lo, hi = SMEARED_ALPHA
    return float(oil[(a > lo) & (a < hi)].sum()) / total


def read_alpha(path: Path, structure: Structure) -> np.ndarray:
    """The oil fraction per cell of the alpha.oil file ``path``, once OpenFOAM has finished
    writing it (raises ValueError while it has not)."""
    return _read_alpha(path, structure)[0]


def mid_gap_alpha(folder: Path, structure: Structure, geom: CaseGeometry) -> np.ndarray:
    """The oil fraction at mid-gap of the time folder ``folder``, per base cell."""
    return structure.mid_gap(_read_alpha(folder / "alpha.oil", structure)[0], geom.n_layers)


def column_raster(columns: np.ndarray, structure: Structure,
                  geom: CaseGeometry) -> metrics.Raster:
    """A per-base-cell oil fraction (at mid-gap, or averaged across the gap) on the raster the
    flow-pattern metrics read (:func:`metrics.raster` with the case's pattern geometry)."""
    return metrics.raster(structure.base_x, structure.base_y, columns, pattern_geometry(geom))


def mid_gap_raster(alpha: np.ndarray, structure: Structure,
                   geom: CaseGeometry) -> metrics.Raster:
    """The cell field ``alpha`` (oil fraction per cell) at mid-gap, rastered as a run's
    metrics read it."""
    return column_raster(structure.mid_gap(alpha, geom.n_layers), structure, geom)


def sample(folder: Path, structure: Structure, geom: CaseGeometry) -> Sample:
    """Read one time folder. Raises (OSError, ValueError, KeyError...) while the folder is
    still being written; the caller retries."""
    alpha, alpha_file = _read_alpha(folder / "alpha.oil", structure)
    volume = _oil_volume(alpha, structure, geom)
    # the oil flux MULES transported (alphaPhi0.oil); where the solver does not write it
    # (interPhaseChangeFoam), phi times the face alpha, and what flows in through the open
    # boundaries times their inletValue (geom.open_inflow_oil: 0, air, but where oil fills
    # the domain; the written face values of inflow faces there are not what was transported)
    oil_flux_file = folder / "alphaPhi0.oil"
    exact = oil_flux_file.exists()
    flux_bf = field_file(oil_flux_file if exact else folder / "phi").boundary_field
    alpha_bf = alpha_file.boundary_field

    def oil_flux(name: str, size: int) -> np.ndarray:
        flux = uniform_or_list(flux_bf[name]["value"], size)
        if not exact:
            flux = flux * np.clip(uniform_or_list(alpha_bf[name]["value"], size), 0.0, 1.0)
            if name != SUPPLY_PATCH:
                flux = np.where(flux > 0.0, flux, flux * geom.open_inflow_oil)
        return flux

    q_in, q_out, out_by_boundary = _in_out(oil_flux, structure, geom)
    out_by_boundary.pop(SUPPLY_PATCH, None)
    r = mid_gap_raster(alpha, structure, geom)
    pattern = metrics.flow_pattern_from_raster(r)
    pattern["bubble_volume_m3"] = _bubble_volume(r, alpha, structure, geom)
    pattern["oil_smeared_fraction"] = smeared_oil_fraction(alpha, structure.cell_volumes)
    p_file = folder / "p"
    p = (uniform_or_list(field_file(p_file).internal_field, len(alpha))
         if p_file.exists() else None)
    pattern["min_pressure_Pa"] = _min_pressure(p, geom)
    pattern["gas_release_m3_s"] = gas_release(p, alpha, structure.cell_volumes, geom)
    pattern["gas_dissolution_m3_s"] = gas_dissolution(p, alpha, structure.cell_volumes, geom)
    gas = _gas(folder, alpha, p, structure, geom) if geom.absolute_pressure else {}
    return Sample(time=float(folder.name), oil_volume=volume, oil_in=q_in, oil_out=q_out,
                  pattern=pattern, oil_flux_exact=exact, oil_out_by_boundary=out_by_boundary,
                  **gas)


def advancing_front_cells(folder: Path, structure: Structure, geom: CaseGeometry,
                          track_half_width: float) -> np.ndarray:
    """Along the flooded region's edge where dry walls run into it, off the track
    (:func:`metrics.advancing_front` of the mid-gap oil at ``folder``): the in-plane size of
    the column there (the square root of its area) over its wall cell's height. A contact line
    advancing onto dry walls holds a capillary suction only where that is within some 15
    (the contact-line strip, :mod:`ehlfoam.case.strip`). Empty without such an edge."""
    r = mid_gap_raster(read_alpha(folder / "alpha.oil", structure), structure, geom)
    points = metrics.advancing_front(r, track_half_width)
    if not len(points):
        return np.empty(0)
    y = np.abs(points[:, 1]) if geom.symmetric else points[:, 1]
    _, i = cKDTree(np.stack([structure.base_x, structure.base_y], 1)).query(
        np.stack([points[:, 0], y], 1))
    return np.sqrt(structure.footprint[i]) / structure.wall_cell[i]


def bare_track_share(folder: Path, structure: Structure, geom: CaseGeometry,
                     track_half_width: float, layers: float, upstream_of: float) -> float | None:
    """The share of the supply track's columns upstream of ``upstream_of`` [m] (x below it,
    |y| within :data:`BARE_TRACK_SPAN` of ``track_half_width`` [m]) whose oil across the gap
    at ``folder`` (:meth:`Structure.column_oil`) is under :data:`BARE_TRACK_OIL` of the
    ``layers`` [m] the supply carries on both walls: near 0 where the layers arrive whole; a
    large share where they broke into drops on the way. None with fewer than 5 such
    columns."""
    sel = ((structure.base_x < upstream_of)
           & (np.abs(structure.base_y) < BARE_TRACK_SPAN * track_half_width))
    if np.count_nonzero(sel) < 5:
        return None
    oil = structure.column_oil(read_alpha(folder / "alpha.oil", structure))
    return float(np.mean(oil[sel] < BARE_TRACK_OIL * layers))


def off_outlet_share(out_by_boundary: dict[str, float]) -> float | None:
    """The share of the oil leaving through the boundaries open to the air (``{boundary:
    outflow}``, any consistent unit) that did not leave through the outlet: near 0 when the
    domain is wide enough; a large share means the flooded region or a wall film reached the
    side or upstream edge. None when nothing left."""
    total = sum(out_by_boundary.values())
    return 1.0 - out_by_boundary.get("outlet", 0.0) / total if total > 0 else None


def _in_out(face_flux, structure: Structure,
            geom: CaseGeometry) -> tuple[float, float, dict[str, float]]:
    """What enters and what leaves (whole contact) through the open boundaries, for
    ``face_flux(patch, size)``: the outward flux of each face of a patch; and what leaves
    through each of them."""
    q_in = 0.0
    out_by_patch: dict[str, float] = {}
    for name in OPEN_PATCHES:
        if name not in structure.patches:
            continue
        flux = face_flux(name, structure.patches[name][1])
        q_in += float(-flux[flux < 0].sum())
        out_by_patch[name] = geom.mirror * float(flux[flux > 0].sum())
    return geom.mirror * q_in, sum(out_by_patch.values()), out_by_patch


def volume_flux(folder: Path, structure: Structure, geom: CaseGeometry) -> tuple[float, float]:
    """The total volume flux [m3/s, whole contact] in and out through the open boundaries at
    one written time, from its phi (oil and gas together)."""
    phi = field_file(folder / "phi").boundary_field
    q_in, q_out, _ = _in_out(lambda name, size: uniform_or_list(phi[name]["value"], size),
                             structure, geom)
    return q_in, q_out


def _gas(folder: Path, alpha: np.ndarray, p: np.ndarray, structure: Structure,
         geom: CaseGeometry) -> dict:
    """Air mass [kg] in the gap and its mass fluxes [kg/s] in and out through the open
    boundaries (whole contact) of a compressible scene: density p/(R T) of the perfect gas
    (``p`` [Pa] per cell), volumetric gas flux phi - alphaPhi0.oil on the boundary faces."""
    temp_file = field_file(folder / "T")
    temp = uniform_or_list(temp_file.internal_field, len(alpha))
    gas = 1.0 - np.clip(alpha, 0.0, 1.0)
    mass = geom.mirror * float(np.sum(gas * p / (AIR_GAS_CONSTANT * temp) * structure.cell_volumes))
    phi = field_file(folder / "phi").boundary_field
    oil = field_file(folder / "alphaPhi0.oil").boundary_field
    p_b, t_b = field_file(folder / "p").boundary_field, temp_file.boundary_field

    def gas_mass_flux(name: str, size: int) -> np.ndarray:
        q = (uniform_or_list(phi[name]["value"], size)
             - uniform_or_list(oil[name]["value"], size))          # outward, m3/s per face
        rho = (uniform_or_list(p_b[name]["value"], size)
               / (AIR_GAS_CONSTANT * uniform_or_list(t_b[name]["value"], size)))
        return rho * q

    m_in, m_out, _ = _in_out(gas_mass_flux, structure, geom)
    return {"gas_mass": mass, "gas_in": m_in, "gas_out": m_out}


def _bubble_volume(r: metrics.Raster, alpha: np.ndarray, structure: Structure,
                   geom: CaseGeometry) -> float:
    """Gas volume [m3, whole contact] in the gap columns under the bubble's footprint."""
    mask = metrics.bubble_mask(r)
    if not mask.any():
        return 0.0
    ix = np.clip(np.rint((structure.base_x - r.x[0]) / r.dx).astype(int), 0, len(r.x) - 1)
    iy = np.clip(np.rint((structure.base_y - r.y[0]) / r.dy).astype(int), 0, len(r.y) - 1)
    under = mask[iy, ix][structure.base_cell]
    gas = 1.0 - np.clip(alpha, 0.0, 1.0)
    return geom.mirror * float(np.sum(gas[under] * structure.cell_volumes[under]))


def gas_release(p: np.ndarray | None, alpha: np.ndarray, cell_volumes: np.ndarray,
                geom: CaseGeometry) -> float | None:
    """Gas the gas-release scene makes [m3/s of gas at its (ambient) density, whole contact]:
    k (pSat - p) alpha_oil per cell volume where p < pSat (Kunz's vaporisation term as
    ehlfoam.case.writer.gas_release_entries writes it; ``p`` the solver's gauge pressure
    [Pa] per cell). None for scenes that release nothing or when p was not written."""
    if p is None or geom.gas_release_rate <= 0.0:
        return None
    deficit = np.maximum(geom.release_pressure_gauge - p, 0.0)
    return geom.mirror * float(geom.gas_release_rate
                               * np.sum(deficit * np.clip(alpha, 0.0, 1.0) * cell_volumes))


def gas_dissolution(p: np.ndarray | None, alpha: np.ndarray, cell_volumes: np.ndarray,
                    geom: CaseGeometry) -> float | None:
    """Gas the gas-release scene dissolves back [m3/s of gas, whole contact]:
    C alpha^2 (1 - alpha) per cell volume where p > pSat (Kunz's condensation term with
    C = geom.gas_dissolution_rate; ``p`` the solver's gauge pressure [Pa] per cell). None
    where nothing dissolves back or p was not written."""
    if p is None or geom.gas_dissolution_rate <= 0.0:
        return None
    a = np.clip(alpha, 0.0, 1.0)
    above = p > geom.release_pressure_gauge
    return geom.mirror * float(geom.gas_dissolution_rate
                               * np.sum((a * a * (1.0 - a) * cell_volumes)[above]))


def _min_pressure(p: np.ndarray | None, geom: CaseGeometry) -> float | None:
    """Lowest absolute pressure [Pa] of the cell pressures ``p``: the cavitating scene's p is
    absolute, the interface scene's is gauge (ambient added). None when p was not written."""
    if p is None:
        return None
    offset = 0.0 if geom.absolute_pressure else geom.ambient_pressure
    return float(p.min() + offset)


def initial_oil_volume(case: Path, structure: Structure, geom: CaseGeometry) -> float:
    """Oil volume at t = 0 [m3, whole contact] from 0.orig."""
    return _oil_volume(_read_alpha(case / "0.orig" / "alpha.oil", structure)[0], structure, geom)
