"""Sweeps over dask: a scheduler address that does not answer is a named error, in bounded
time (issue 10: it hung past dask's own timeout)."""

from __future__ import annotations

import socket
import time

import pytest

from runtime.studies.sweep import SchedulerError, run_cases


def _double(x: int) -> int:
    return 2 * x


def test_silent_scheduler_is_a_named_error_in_bounded_time():
    # a listening socket that never answers: the kernel accepts connections for it
    with socket.socket() as server:
        server.bind(("127.0.0.1", 0))
        server.listen(8)
        address = f"tcp://127.0.0.1:{server.getsockname()[1]}"
        start = time.perf_counter()
        with pytest.raises(SchedulerError, match=f"--scheduler {address}: cannot connect"):
            run_cases(_double, [{"x": 1}, {"x": 2}], scheduler=address, connect_timeout_s=1.0)
        assert time.perf_counter() - start < 15.0


def test_nothing_listening_is_a_named_error():
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        port = probe.getsockname()[1]
    with pytest.raises(SchedulerError, match="cannot connect to a dask scheduler"):
        run_cases(_double, [{"x": 1}, {"x": 2}], scheduler=f"tcp://127.0.0.1:{port}",
                  connect_timeout_s=1.0)


def test_serial_sweep_keeps_the_order():
    assert run_cases(_double, [{"x": 3}, {"x": 1}], serial=True) == [6, 2]
