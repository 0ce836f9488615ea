"""The Python API in ten lines: the nominal case on a coarse mesh for a twentieth of a transit
(seconds), written, run, and read back. ``python examples/api.py [OUT]`` (default: a new
temporary folder)."""

import sys
import tempfile
from pathlib import Path

import ehlfoam

out = Path(sys.argv[1] if len(sys.argv) > 1 else tempfile.mkdtemp(prefix="ehlfoam-")) / "nominal"
spec = ehlfoam.load_case_spec(Path(__file__).parent / "cases" / "nominal.toml",
                              **{"mesh.resolution": "coarse", "run.transits_max": 0.05})
geometry = ehlfoam.write_case(spec, out)
metrics = ehlfoam.run_case(out)
print(f"{out}: {geometry.cells} cells, {metrics['status']}, state {metrics['state']}")
print(f"inlet meniscus {metrics['inlet_meniscus_distance_over_a']:.2f} a upstream, "
      f"flooded width {metrics['flooded_width_over_a']:.2f} a")
