"""Run folders, scene files and files written whole: the comparison layer's reading and writing."""
