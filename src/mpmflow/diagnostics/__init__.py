"""What a run measures: ``measures`` (the front, the column's height, volumes and volume
fractions, energies, the water's binned state) and ``probes`` (pressure sensors and level
gauges at fixed points, and their windows)."""
