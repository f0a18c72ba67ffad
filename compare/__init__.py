"""dem.compare: the comparison layer of the dem engine with LIGGGHTS, YADE and LAMMPS, and its
figures (docs/compare.md). The checkout's compare/, imported as part of the package dem."""
