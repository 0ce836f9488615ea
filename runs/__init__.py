"""Running OpenFOAM cases, the ehlfoam command line and its runtime."""
