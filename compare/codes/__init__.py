"""The compared codes: LIGGGHTS, LAMMPS, YADE and the native engine (translation, running, reading)."""
