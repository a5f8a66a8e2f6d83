"""Files from the bench: measurement readers (CSV, HDF5) and the atomic figure writer."""
