"""The verdict: the pipeline, the read-back probes, the judges, the report."""
