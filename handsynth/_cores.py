"""The CPU cores this process may use, the one count every default of workers comes from."""

from __future__ import annotations

import os

__all__ = ["usable_cores"]


def usable_cores() -> int:
    """CPU cores this process may run on, at least 1.

    Its CPU affinity where the system keeps one (Linux: a container's cpuset or
    ``taskset`` can leave a process 2 of a machine's 64 cores, and 64 workers
    on 2 cores would only wait on each other), else every core of the machine.
    """
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except AttributeError:  # no affinity on this platform (macOS, Windows)
        return os.cpu_count() or 1
