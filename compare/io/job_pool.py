"""The one job pool of a comparison and of every study: ``--jobs`` places for the runs, and
figure processes for the pictures.

A run is a task of a thread that starts a program (the engine or a reference code) and waits for
it. A picture is drawn in a figure process, forked from a server that imported the figure module
once (a fork of a process that runs threads could inherit a held lock): ``draw`` starts it at
once, beside the runs (up to ``jobs`` figure processes); ``drawn`` waits for it, so that a run
task that calls it holds one of the places while its picture is drawn (no more programs run or
draw at a time than there are places).

    with JobPool(jobs, figures="dem.compare.figures.runs") as pool:
        done = [pool.run(run_one, case) for case in cases]
        picture = pool.draw(plot, run_dir, png)

``in_order(fn, items, jobs)``: fn over the items, up to ``jobs`` at once, the results in the
items' order (one job: in this thread).
"""
from __future__ import annotations

import concurrent.futures as cf
import multiprocessing as mp
import os


class JobPool:
    def __init__(self, jobs: int, figures: str | None = None):
        """jobs: the places (at least 1); figures: the module the figure processes import once
        (none: a pool of runs only)."""
        self.jobs = max(1, int(jobs))
        self._figures = figures
        self._runs = None
        self._pictures = None

    def __enter__(self) -> "JobPool":
        self._runs = cf.ThreadPoolExecutor(max_workers=self.jobs)
        if self._figures:
            ctx = mp.get_context("forkserver")
            ctx.set_forkserver_preload([self._figures])
            self._pictures = cf.ProcessPoolExecutor(max_workers=self.jobs, mp_context=ctx)
            self._pictures.submit(os.getpid)   # the fork server starts beside the first runs
        return self

    def __exit__(self, *exc) -> None:
        self._runs.shutdown()                  # the drawing tasks wait on the figure processes
        if self._pictures is not None:
            self._pictures.shutdown()

    def run(self, fn, *args, **kwargs) -> cf.Future:
        """fn(*args, **kwargs) as a task of the pool (one place while it runs)."""
        return self._runs.submit(fn, *args, **kwargs)

    def drawn(self, fn, *args):
        """fn(*args) in a figure process, waited for; its result (its error raised here)."""
        return self.draw(fn, *args).result()

    def draw(self, fn, *args) -> cf.Future:
        """fn(*args) in a figure process, started at once beside the runs."""
        if self._pictures is None:
            raise RuntimeError("JobPool: a pool without figures draws nothing")
        return self._pictures.submit(fn, *args)


def in_order(fn, items, jobs: int) -> list:
    """[fn(item) for item in items], up to ``jobs`` at once (a JobPool's runs), in the items' order."""
    items = list(items)
    jobs = max(1, min(int(jobs), len(items)))
    if jobs == 1:
        return [fn(item) for item in items]
    with JobPool(jobs) as pool:
        return [f.result() for f in [pool.run(fn, item) for item in items]]
