"""Independent jobs on worker processes (rcengine.parallel.run_jobs): the same results, in order,
whether they run in this process or in a pool."""

from __future__ import annotations

import os
from dataclasses import dataclass

from rcengine.parallel import run_jobs


@dataclass(frozen=True)
class _Square:
    x: int

    def run(self) -> tuple[int, int]:
        return self.x * self.x, os.getpid()


def test_jobs_come_back_in_order_from_worker_processes():
    jobs = [_Square(x) for x in range(7)]
    pooled = run_jobs(jobs, workers=2)
    assert [value for value, _ in pooled] == [x * x for x in range(7)]
    assert all(pid != os.getpid() for _, pid in pooled)


def test_one_worker_or_one_job_runs_in_this_process():
    for jobs, workers in (([_Square(x) for x in range(3)], 1), ([_Square(5)], 4)):
        results = run_jobs(jobs, workers)
        assert [value for value, _ in results] == [job.x * job.x for job in jobs]
        assert {pid for _, pid in results} == {os.getpid()}
