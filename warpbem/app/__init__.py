"""Application layer: scene files, runs, sweeps, HDF5 output, XDMF, plots and the command line."""
