"""One module per scene; each is a thin command line over the Python API."""
