"""The record a written case carries in its ``ehlfoam/`` folder: its spec and the numbers of
its geometry (:class:`CaseGeometry`) that the run, the metrics and the reports read, and what
is wrong with its mesh though it runs (:func:`mesh_warnings`)."""

from __future__ import annotations

import json
import os
from dataclasses import dataclass
from pathlib import Path

from ehlfoam.errors import SpecError
from ehlfoam.notices import Notice
from ehlfoam.spec.case import CaseSpec
from ehlfoam.spec.sections import DomainBox

META = "ehlfoam"  # the case's own folder of generator outputs


@dataclass(frozen=True)
class CaseGeometry:
    """Numbers of a generated case that the run, the metrics and the reports need (SI)."""

    a: float
    radius: float
    speed: float
    x_min: float
    x_max: float
    y_max: float
    island_radius: float
    symmetric: bool
    n_layers: int
    cells: int
    transit_time: float
    end_time: float
    write_interval: float
    max_delta_t: float
    capillary_limit: str
    min_cell_size: float
    island_gap: float
    hc: float
    contact_flow: float
    gap_mismatch: float
    oil_viscosity: float
    oil_density: float
    solver: str = "interFoam"
    ambient_pressure: float = 1.013e5
    #: the gas-release scene's k [1/(Pa s)] (0: the scene releases nothing), its release
    #: pressure as the solver's gauge pSat [Pa], the oil's Bunsen coefficient for air, and
    #: the rate C [1/s] at which its gas dissolves back (0: never)
    gas_release_rate: float = 0.0
    gas_dissolution_rate: float = 0.0
    release_pressure_gauge: float = 0.0
    air_solubility: float = 0.09
    #: median over the base cells of the wall-cell heights the ball surface steps across a
    #: cell (ehlfoam.mesh.wall_steps); above BALL_WALL_STEPS_LIMIT a spurious film creeps
    #: along the ball (0: not computed, a case written before it existed)
    ball_wall_steps: float = 0.0
    #: the oil fraction of what flows in through the boundaries open to the outside: 0 (air)
    #: but where oil fills the domain (single-phase scene, submerged supply)
    open_inflow_oil: float = 0.0

    @property
    def box(self) -> DomainBox:
        """The meshed domain's rectangle [m] (the one record the mesh and the metrics
        extend)."""
        return DomainBox(x_min=self.x_min, x_max=self.x_max, y_max=self.y_max,
                         island_radius=self.island_radius, symmetric=self.symmetric)

    @property
    def mirror(self) -> float:
        """Factor from the meshed domain to the whole contact: 2 for a half domain, else 1."""
        return 2.0 if self.symmetric else 1.0

    @property
    def absolute_pressure(self) -> bool:
        """The solver's p is absolute (compressible scenes), else gauge (0 = ambient)."""
        return self.solver.startswith("compressible")

    @property
    def log_name(self) -> str:
        """The solver's log file in the case folder."""
        return f"log.{self.solver}"


#: the median ball wall steps (ehlfoam.mesh.wall_steps) above which a case is flagged: the
#: three levels give 7-9; at 15-90 (thinner wall cells under the same in-plane cells) a
#: spurious oil film creeps along the ball beside the flooded region and 10-54 % of the
#: outflow leaves through the side (docs/models/interface.md#ball-wall-steps)
BALL_WALL_STEPS_LIMIT = 10.0


def mesh_warnings(geom: CaseGeometry) -> list[Notice]:
    """What is wrong with a written case's mesh though it runs: the ball's wall cells
    stair-stepping above :data:`BALL_WALL_STEPS_LIMIT`. `ehlfoam case` prints these, and every
    run records them in metrics.json (``warnings``), which a batch shows."""
    if geom.ball_wall_steps <= BALL_WALL_STEPS_LIMIT:
        return []
    return [Notice("ball-wall-steps",
                   f"the ball's wall cells step {geom.ball_wall_steps:.1f} heights per cell "
                   f"(above {BALL_WALL_STEPS_LIMIT:g}): a spurious oil film creeps along the "
                   f"ball, thin mesh.n_layers need finer in-plane cells",
                   "docs/models/interface.md#ball-wall-steps")]


class CaseFileError(SpecError):
    """A record of a written case (``ehlfoam/spec.json``, ``ehlfoam/geometry.json``) that
    cannot be read: corrupt, or not written by ehlfoam."""


def _read_record(case: str | os.PathLike, name: str, parse):
    """``parse(text)`` of ``case/ehlfoam/NAME``; :class:`CaseFileError` naming the file and
    why if it is not what ehlfoam wrote (FileNotFoundError if it is missing)."""
    data = (Path(case) / META / name).read_bytes()
    try:
        return parse(data.decode("utf-8"))
    except (ValueError, TypeError) as err:   # JSON, pydantic, UTF-8 errors are ValueErrors
        if hasattr(err, "errors"):            # pydantic: its first problems, one line
            why = "; ".join(f"{'.'.join(map(str, e['loc']))}: {e['msg']}" if e["loc"]
                            else e["msg"] for e in err.errors()[:3])
        else:
            why = str(err).splitlines()[0] if str(err) else type(err).__name__
        raise CaseFileError(f"case {case}: {META}/{name} is corrupt ({why}); write the case "
                            f"again (ehlfoam case SPEC --out {case} --overwrite)") from None


def load_geometry(case: str | os.PathLike) -> CaseGeometry:
    """The :class:`CaseGeometry` a generated case was written with (:class:`CaseFileError`
    if its record is corrupt)."""
    return _read_record(case, "geometry.json", lambda text: CaseGeometry(**json.loads(text)))


def load_spec_of(case: str | os.PathLike) -> CaseSpec:
    """The spec a generated case was written from (:class:`CaseFileError` if its record is
    corrupt)."""
    return _read_record(case, "spec.json", CaseSpec.model_validate_json)
