"""Shared test fixtures: an isolated ROS domain per test run, processes that always stop, an
in-test rclpy node that spins until a condition holds or a bounded wait runs out, and the check
of a LegFkError's message."""

from __future__ import annotations

import contextlib
import os
import signal
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import pytest
from shared import claim_domain_id

from a1_leg_fk.model.urdf import LegFkError

# Set before rclpy is imported anywhere, so the in-test nodes and every child share the domain.
DOMAIN_ID, _DOMAIN_LOCK = claim_domain_id()
os.environ["ROS_DOMAIN_ID"] = str(DOMAIN_ID)
os.environ["ROS_AUTOMATIC_DISCOVERY_RANGE"] = "LOCALHOST"
os.environ.pop("ROS_LOCALHOST_ONLY", None)
os.environ["PYTHONUNBUFFERED"] = "1"

BIN = Path(sys.executable).parent
DEFAULT_WAIT_S = 20.0
FAMILY_NOISE_SEED = 7
"""The seed of every contact-family run's noisy twin."""


@contextlib.contextmanager
def raises_leg_fk_error(*culprits: str) -> Iterator[pytest.ExceptionInfo]:
    """Expect a LegFkError, which must also be a ValueError, whose message names every culprit."""
    with pytest.raises(LegFkError) as info:
        yield info
    assert isinstance(info.value, ValueError)
    for culprit in culprits:
        assert culprit in str(info.value), f"{culprit!r} not named in: {info.value}"


class Processes:
    """Starts child processes with output in files, and stops every one of them at teardown."""

    def __init__(self, folder: Path) -> None:
        self._folder = folder
        self._started: list[tuple[subprocess.Popen, Path]] = []

    def start(self, command: list[str], env: dict[str, str] | None = None) -> subprocess.Popen:
        log = self._folder / f"process{len(self._started)}.log"
        process = subprocess.Popen(
            command,
            stdout=open(log, "w"),  # noqa: SIM115 (closed with the process)
            stderr=subprocess.STDOUT,
            env={**os.environ, **(env or {})},
            start_new_session=True,
        )
        self._started.append((process, log))
        return process

    def output(self, process: subprocess.Popen) -> str:
        """Everything the process printed so far (stdout and stderr)."""
        for started, log in self._started:
            if started is process:
                return log.read_text(errors="replace")
        raise KeyError(process)

    def interrupt(self, process: subprocess.Popen, timeout_s: float = 5.0) -> int:
        """Send SIGINT (as Ctrl-C does) and return the exit code, killing it after
        ``timeout_s``."""
        if process.poll() is None:
            process.send_signal(signal.SIGINT)
        try:
            return process.wait(timeout_s)
        except subprocess.TimeoutExpired:
            process.kill()
            process.wait(5)
            raise

    def stop_all(self) -> None:
        for process, _ in self._started:
            if process.poll() is None:
                process.send_signal(signal.SIGINT)
        deadline = time.monotonic() + 5.0
        for process, _ in self._started:
            try:
                process.wait(max(0.1, deadline - time.monotonic()))
            except subprocess.TimeoutExpired:
                os.killpg(process.pid, signal.SIGKILL)
                process.wait(5)


@pytest.fixture
def processes(tmp_path: Path) -> Iterator[Processes]:
    started = Processes(tmp_path)
    yield started
    started.stop_all()


class RosProbe:
    """An rclpy node of the test's own, in its own context, spun only while waiting."""

    def __init__(self) -> None:
        import rclpy
        from rclpy.executors import SingleThreadedExecutor

        self._rclpy = rclpy
        self.context = rclpy.Context()
        rclpy.init(context=self.context)
        self.node = rclpy.create_node(f"test_probe_{os.getpid()}", context=self.context)
        self.executor = SingleThreadedExecutor(context=self.context)
        self.executor.add_node(self.node)

    def spin_until(self, condition: Callable[[], bool], timeout_s: float = DEFAULT_WAIT_S) -> bool:
        """Spin until ``condition()`` is true (returns True) or ``timeout_s`` passes (False)."""
        deadline = time.monotonic() + timeout_s
        while not condition():
            if time.monotonic() > deadline:
                return False
            self.executor.spin_once(timeout_sec=0.02)
        return True

    def spin_for(self, seconds: float) -> None:
        """Spin for a fixed time (to collect messages that should, or should not, arrive)."""
        deadline = time.monotonic() + seconds
        while time.monotonic() < deadline:
            self.executor.spin_once(timeout_sec=0.02)

    def call(self, client, request, timeout_s: float = DEFAULT_WAIT_S, attempt_s: float = 3.0):
        """Call a service and return its response, asking again every ``attempt_s`` seconds.

        A request can reach a server before the server has matched the client's response reader;
        Fast DDS then drops the response ("failed to send response (timeout)"). The requests the
        tests send are idempotent, so asking again is safe.
        """
        deadline = time.monotonic() + timeout_s
        assert self.spin_until(client.service_is_ready, timeout_s), (
            f"service {client.srv_name} not offered"
        )
        while time.monotonic() < deadline:
            future = client.call_async(request)
            if self.spin_until(future.done, min(attempt_s, max(0.0, deadline - time.monotonic()))):
                return future.result()
            client.remove_pending_request(future)
        raise AssertionError(f"service {client.srv_name} did not answer within {timeout_s} s")

    def close(self) -> None:
        self.executor.shutdown()
        self.node.destroy_node()
        self._rclpy.shutdown(context=self.context)


@pytest.fixture
def ros() -> Iterator[RosProbe]:
    probe = RosProbe()
    yield probe
    probe.close()


def family_folder() -> Path:
    """Where the contact family's runs are kept between sessions: the system's temporary
    folder (make test runs pytest without its cache)."""
    return Path(tempfile.gettempdir()) / "a1_leg_fk-contact-runs"


@pytest.fixture(scope="session")
def family() -> dict[str, Any]:
    """The contact family (test/contact_runs.py): every run, clean and with sensor noise (seed
    :data:`FAMILY_NOISE_SEED`), simulated once per machine (:func:`family_folder`; the files are
    named after the simulation's sources) and loaded once per session."""
    from contact_runs import contact_runs, with_noise

    clean = contact_runs(family_folder())
    noisy = {f"{n}+noise": with_noise(run, FAMILY_NOISE_SEED) for n, run in clean.items()}
    return {**clean, **noisy}
