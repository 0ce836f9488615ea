"""Case generator: gap -> mesh -> OpenFOAM case files."""
