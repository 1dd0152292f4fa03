"""A sweep's store under faults (issue 21): two runs at once, a store that cannot be written, a
full disk, an error inside a worker, a scheduler that does not answer.

Each fault ends ``flexsat run`` with a clear message naming the store (or the field) and exit
code 2, never a traceback, and the store stays resumable: the next run completes it to the
store of an uninterrupted run, compared variable by variable, bit for bit.

The sweep is the TAMU Law II slew (seed 000 Att. 3 §V) over 4 × 2 (α, u_max) points, 2 modes,
12 s at 50 Hz, in chunks of 2 cases, with the hub angle recorded over time (its chunk files are
what a full disk refuses).
"""

from __future__ import annotations

import errno
import json
import os
import resource
import signal
import socket
import subprocess
import sys
import threading
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

from flexsat import file_locks
from flexsat.cases import tamu
from flexsat.cli import app
from flexsat.design import batch_cluster
from flexsat.design.batch_runner import (
    BatchInterrupted,
    HubManeuverBuilder,
    open_results,
    run_batch,
)
from flexsat.design.batch_store import StoreInUse, StoreLock
from flexsat.input_checks import FieldError
from flexsat.scenarios import load_scenario, run_scenario
from flexsat.sim import SimulationDiverged
from flexsat.sim.engine import offset_cases

SRC = Path(__file__).resolve().parents[2] / "src"
runner = CliRunner()

MANEUVER = """
name: short TAMU slew
case: tamu
model: {n_modes: 2, stiffening: false}
maneuver: {angle: "40 deg"}
simulation: {duration: "12 s", control_rate: "50 Hz", settling_band: "0.5 deg", seed: 0}
actuator: {saturation: "400 ozf*in"}
runs:
  - {label: "Law II", law: lyapunov_tracker, gains: {g1: "3000 ozf*in/rad", g2: "800 ozf*in*s/rad"},
     reference: {shape: smooth_bang_bang, alpha: 0.2, u_max: "400 ozf*in"}}
"""

SWEEP = """
kind: sweep
name: tiny trade grid
scenario: maneuver.yaml
run: Law II
parameters:
  alpha: {values: [0.0, 0.1, 0.2, 0.25]}
  u_max: {values: ["300 ozf*in", "500 ozf*in"]}
histories: [theta]
execution: {chunk_size: 2}
store: store.zarr
"""


def _sweep(folder: Path) -> Path:
    folder.mkdir(parents=True, exist_ok=True)
    (folder / "maneuver.yaml").write_text(MANEUVER)
    (folder / "sweep.yaml").write_text(SWEEP)
    return folder / "sweep.yaml"


def _values(store: Path) -> dict[str, np.ndarray]:
    ds = open_results(store)
    return {name: ds[name].values for name in ds.variables}


def _same(a: dict, b: dict) -> None:
    """Bit-identical data: the same variables with the same bytes (NaN where NaN)."""
    assert sorted(a) == sorted(b)
    for name in a:
        assert a[name].dtype == b[name].dtype, name
        assert np.array_equal(a[name], b[name], equal_nan=a[name].dtype.kind == "f"), name


@pytest.fixture(scope="module")
def reference_store(tmp_path_factory) -> Path:
    """The sweep run once, uninterrupted, in its own folder."""
    sweep = _sweep(tmp_path_factory.mktemp("reference"))
    run_scenario(load_scenario(sweep))
    return sweep.parent / "store.zarr"


@pytest.fixture(scope="module")
def reference(reference_store) -> dict[str, np.ndarray]:
    return _values(reference_store)


def _interrupted(sweep: Path, chunks: int) -> None:
    """Run ``sweep`` until ``chunks`` chunks are stored, then stop it as Ctrl-C would."""
    seen = []

    def stop(label: str) -> None:
        seen.append(label)
        if len(seen) > chunks:  # the first call reports the start
            raise KeyboardInterrupt

    with pytest.raises(BatchInterrupted):
        run_scenario(load_scenario(sweep), progress=stop)


def _env() -> dict[str, str]:
    return {**os.environ, "PYTHONPATH": str(SRC), "OMP_NUM_THREADS": "1"}


def _flexsat(sweep: Path, out: str, **kwargs) -> subprocess.Popen:
    return subprocess.Popen(
        [sys.executable, "-m", "flexsat", "run", str(sweep), "--out", str(sweep.parent / out)],
        env=_env(),
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        **kwargs,
    )


def _one_line(text: str) -> str:
    return " ".join(text.split())


def _wait_for_holder(run: subprocess.Popen, lock: Path) -> None:
    """Wait until ``run`` holds the store of the lock file ``lock``."""
    deadline = time.monotonic() + 300
    while not (lock.exists() and lock.read_text()):
        assert run.poll() is None, run.communicate()
        assert time.monotonic() < deadline, "the run never took the store"
        time.sleep(0.02)
    assert json.loads(lock.read_text())["pid"] == run.pid


# -- two runs at once ----------------------------------------------------------------------------
def test_two_runs_at_once_one_completes_the_other_is_refused_naming_it(tmp_path, reference):
    """Two ``flexsat run`` of one sweep at once: the second is refused with exit code 2, naming
    the first (its process id and command) and changing nothing; the first completes to the
    store of an uninterrupted run. The first is held (SIGSTOP) once it holds the store, so the
    second meets it whatever the machine's speed."""
    sweep = _sweep(tmp_path)
    lock = tmp_path / ".store.zarr.lock"
    first = _flexsat(sweep, "first")
    try:
        _wait_for_holder(first, lock)
        os.kill(first.pid, signal.SIGSTOP)
        try:
            second = _flexsat(sweep, "second")
            _, err = second.communicate(timeout=300)
        finally:
            os.kill(first.pid, signal.SIGCONT)
        assert second.returncode == 2, err
        message = _one_line(err)
        assert f"store: cannot write the batch store to '{tmp_path / 'store.zarr'}'" in message
        assert f"another flexsat run is filling it (pid {first.pid} on host" in message
        assert f"python -m flexsat run {sweep} --out {tmp_path / 'first'}" in message
        assert "Nothing was changed" in message and "Traceback" not in err
        assert not (tmp_path / "second").exists()
        _, err = first.communicate(timeout=300)
    finally:
        if first.poll() is None:
            first.kill()
    assert first.returncode == 0, err
    assert not lock.exists()
    _same(_values(tmp_path / "store.zarr"), reference)


def _dead_pid() -> int:
    child = subprocess.Popen([sys.executable, "-c", "pass"])
    child.wait()
    return child.pid


def test_a_lock_left_by_a_killed_run_is_stale_and_taken_over(tmp_path, reference):
    """A run killed with SIGKILL once it holds the store leaves its lock file behind; the kernel
    has released its lock, so the next run takes it over and completes the store."""
    sweep = _sweep(tmp_path)
    lock = tmp_path / ".store.zarr.lock"
    killed = _flexsat(sweep, "killed")
    _wait_for_holder(killed, lock)
    killed.kill()
    killed.wait()
    assert json.loads(lock.read_text())["pid"] == killed.pid
    run_scenario(load_scenario(sweep))
    assert not lock.exists()
    _same(_values(tmp_path / "store.zarr"), reference)


def test_a_held_store_is_refused_and_left_as_it_was(tmp_path):
    store = tmp_path / "s.zarr"
    with StoreLock(store):
        with pytest.raises(StoreInUse) as info:
            with StoreLock(store):
                pass
    assert info.value.errno == errno.EBUSY and info.value.store == store
    assert f"(pid {os.getpid()} on host {socket.gethostname()!r}, started " in str(info.value)
    assert not store.exists() and not (tmp_path / ".s.zarr.lock").exists()


def test_one_store_is_one_lock_however_its_path_is_spelled(tmp_path):
    """A store reached through a linked folder or a relative path holds the same lock."""
    (tmp_path / "real").mkdir()
    (tmp_path / "link").symlink_to(tmp_path / "real")
    with StoreLock(tmp_path / "link" / "s.zarr"):
        with pytest.raises(StoreInUse):
            with StoreLock(tmp_path / "real" / ".." / "real" / "s.zarr"):
                pass
        assert (tmp_path / "real" / ".s.zarr.lock").exists()


@pytest.fixture
def no_kernel_locks(monkeypatch):
    """A file system without flock (some NFS set-ups)."""

    def unsupported(fd, operation):
        raise OSError(errno.ENOLCK, "No locks available")

    monkeypatch.setattr(file_locks.fcntl, "flock", unsupported)


def test_without_kernel_locks_a_dead_holder_is_stale_and_a_live_one_refused(
    tmp_path, no_kernel_locks
):
    """Without flock the lock file's record decides: a holder of this host whose process is
    gone is taken over; a live one (here a sleeping process) is refused, the message naming
    the lock file to remove if that run is in fact gone."""
    store = tmp_path / "s.zarr"
    lock = tmp_path / ".s.zarr.lock"
    lock.write_text(json.dumps({"pid": _dead_pid(), "host": socket.gethostname()}))
    with StoreLock(store):
        assert json.loads(lock.read_text())["pid"] == os.getpid()
    assert not lock.exists()
    sleeper = subprocess.Popen([sys.executable, "-c", "import time; time.sleep(60)"])
    try:
        lock.write_text(json.dumps({"pid": sleeper.pid, "host": socket.gethostname()}))
        with pytest.raises(StoreInUse, match=f"pid {sleeper.pid} .*remove '{lock}'"):
            with StoreLock(store):
                pass
        lock.write_text(json.dumps({"pid": 1, "host": "another-host.invalid"}))
        with pytest.raises(StoreInUse, match="on host 'another-host.invalid'"):
            with StoreLock(store):
                pass
    finally:
        sleeper.kill()
        sleeper.wait()


# -- a store that cannot be written ------------------------------------------------------------
def _block_writes(store: Path) -> None:
    """Make the store refuse the writes of the chunks still to run: read-only folders for an
    ordinary user; for root, whom permissions do not stop, a non-empty folder in the place of
    every missing chunk file of one variable (zarr cannot rename its new file onto it)."""
    if os.geteuid() != 0:
        for folder, _, _ in os.walk(store):
            os.chmod(folder, 0o555)
        return
    done = open_results(store)["done"].values
    for chunk in range(len(done) // 2):
        if not done[2 * chunk : 2 * chunk + 2].any():
            obstacle = store / "metric_overshoot_deg" / "c" / str(chunk) / "obstacle"
            obstacle.mkdir(parents=True)


def _unblock(store: Path) -> None:
    if os.geteuid() != 0:
        for folder, _, _ in os.walk(store):
            os.chmod(folder, 0o755)
        return
    for chunk in (store / "metric_overshoot_deg" / "c").iterdir():
        if chunk.is_dir():
            (chunk / "obstacle").rmdir()
            chunk.rmdir()


def test_a_store_that_cannot_be_written_exits_2_naming_it_and_resumes(tmp_path, reference):
    sweep = _sweep(tmp_path)
    store = tmp_path / "store.zarr"
    _interrupted(sweep, 1)
    _block_writes(store)
    try:
        done = runner.invoke(app, ["run", str(sweep), "--out", str(tmp_path / "out")])
    finally:
        _unblock(store)
    assert done.exit_code == 2, done.output
    message = _one_line(done.stderr)
    assert f"store: cannot write the batch store to '{store}': " in message
    assert "The store keeps 2 of 8 cases; run the same command again to resume it." in message
    assert not (tmp_path / "out").exists()
    run_scenario(load_scenario(sweep))
    _same(_values(store), reference)


@pytest.mark.parametrize(
    "place",
    ["/proc/flexsat-sweep/store.zarr", "/proc/store.zarr", "{tmp}/" + "x" * 300 + ".zarr"],
)
def test_a_store_that_cannot_be_made_exits_2_naming_it(tmp_path, place):
    """No folder can be made under /proc, nor a name of 300 characters: named, not a
    traceback, before any case runs."""
    sweep = _sweep(tmp_path)
    place = place.format(tmp=tmp_path)
    sweep.write_text(SWEEP.replace("store: store.zarr", f"store: {place}"))
    done = runner.invoke(app, ["run", str(sweep), "--out", str(tmp_path / "out")])
    assert done.exit_code == 2, done.output
    message = _one_line(done.stderr)
    assert f"store: cannot write the batch store to '{place}': " in message
    assert message.endswith("No store was made; run the same command again once it can be written.")


def test_a_full_disk_exits_2_naming_the_store_and_resumes(tmp_path, reference_store, reference):
    """A file-size limit (``ulimit -f``, SIGXFSZ ignored as Python does) below the size of a
    history chunk file and above the report's 4 KiB probe: the run stops at the first chunk it
    computes, exit code 2, naming the store and the limit; the next run completes the store."""
    largest = max(f.stat().st_size for f in (reference_store / "history_theta").rglob("*"))
    sweep = _sweep(tmp_path)
    store = tmp_path / "store.zarr"
    _interrupted(sweep, 1)
    limit = 4096 + 1024
    assert largest > limit, f"a history chunk file of {largest} B is not refused below {limit} B"

    def limited() -> None:
        signal.signal(signal.SIGXFSZ, signal.SIG_IGN)
        resource.setrlimit(resource.RLIMIT_FSIZE, (limit, limit))

    run = _flexsat(sweep, "out", preexec_fn=limited)
    _, err = run.communicate(timeout=300)
    assert run.returncode == 2, err
    message = _one_line(err)
    assert f"store: cannot write the batch store to '{store}': File too large" in message
    assert "ulimit -f" in message and "The store keeps 2 of 8 cases" in message
    assert "Traceback" not in err
    run_scenario(load_scenario(sweep))
    _same(_values(store), reference)


# -- errors inside a worker ------------------------------------------------------------------------
@pytest.fixture(scope="module")
def builder() -> HubManeuverBuilder:
    case = tamu(n_modes=2)
    return HubManeuverBuilder(
        case.params,
        2,
        case.sim_config(duration=0.5),
        case.angle,
        case.reference_inertia,
        u_max=case.max_torque,
        g1=1.0,
        g2=1.0,
    )


@dataclass(frozen=True)
class Refusing:
    """A case builder whose third and fourth cases raise ``error`` inside the worker, counting
    its calls in the file ``calls``."""

    build: HubManeuverBuilder
    error: ValueError
    calls: Path

    def __call__(self, parameters, seeds):
        with self.calls.open("a") as f:
            f.write(f"{parameters['alpha'][0]}\n")
        if 0.5 in parameters["alpha"]:
            raise self.error
        return self.build(parameters, seeds)


@pytest.mark.parametrize(
    "error",
    [
        FieldError("parameters['alpha']", "must be <= 1/4, got 0.5"),
        FieldError("parameters['alpha']", "must be <= 1/4, got " + ", ".join(["0.5"] * 4000)),
        SimulationDiverged(
            "simulation diverged at t = 0.25 s (sample 5) in case(s) 1: too high",
            (1,),
            0.25,
            "the gains are too high",
        ),
    ],
    ids=["FieldError", "FieldError, a long message", "SimulationDiverged"],
)
def test_an_error_inside_a_worker_keeps_its_type_and_fields_and_is_not_retried(
    builder, tmp_path, error
):
    """The chunk's own exception, with its attributes (a FieldError's field, a
    SimulationDiverged's cases), raised once: the same chunk would raise it again on every
    retry. dask's own transport rebuilds a message over 10,000 characters as
    ``type(e)("Long error message", text)``: a FieldError of the field "Long error message",
    and a bare Exception for a class whose __init__ takes more than its message."""
    calls = tmp_path / "calls"
    alpha = np.array([0.0, 0.1, 0.5, 0.5])
    with pytest.raises(type(error)) as info:
        run_batch(
            Refusing(builder, error, calls),
            {"alpha": alpha},
            tmp_path / "s.zarr",
            chunk_size=2,
            retries=2,
        )
    # a divergence is named by the batch's case numbers: case 1 of the chunk from case 2 is 3
    expected = offset_cases(error, 2) if isinstance(error, SimulationDiverged) else error
    assert type(info.value) is type(error) and str(info.value) == str(expected)
    assert vars(info.value) == vars(expected)
    assert calls.read_text().split().count("0.5") == 1  # run once, though retries=2


def test_an_unknown_history_is_a_field_error_of_histories(builder, tmp_path):
    with pytest.raises(FieldError) as info:
        run_batch(builder, {"alpha": np.array([0.0, 0.1])}, tmp_path / "s.zarr", histories=("x",))
    assert info.value.field == "histories"


# -- a scheduler that does not answer -----------------------------------------------------------
@pytest.fixture
def server():
    """A TCP server on a free port that treats each connection with ``serve(connection)``."""
    listener = socket.socket()
    listener.bind(("127.0.0.1", 0))
    listener.listen()
    held = []

    def start(serve):
        def loop():
            while True:
                try:
                    connection, _ = listener.accept()
                except OSError:
                    return
                held.append(connection)
                serve(connection)

        threading.Thread(target=loop, daemon=True).start()
        return f"tcp://127.0.0.1:{listener.getsockname()[1]}"

    yield start
    listener.close()
    for connection in held:
        connection.close()


@pytest.mark.parametrize(
    "serve, why",
    [
        (lambda connection: None, "nothing answered within 1 s"),
        (
            lambda connection: connection.sendall(b"HTTP/1.1 400 Bad Request\r\n\r\n"),
            "the connection failed",
        ),
    ],
    ids=["silent", "not dask"],
)
def test_a_scheduler_address_where_no_scheduler_answers_is_refused_by_field(
    builder, tmp_path, server, serve, why, monkeypatch
):
    """A server that accepts and stays silent (distributed's handshake alone would wait for it
    forever) or answers in another protocol (read as a message length: a MemoryError): a
    FieldError of ``scheduler`` naming the address; ``flexsat run`` exits with code 2. (The
    connection timeout is cut to 1 s for the test.)"""
    monkeypatch.setattr(batch_cluster, "CONNECT_TIMEOUT", 1.0)
    address = server(serve)
    with pytest.raises(FieldError, match=f"no dask scheduler answered at '{address}': {why}") as e:
        run_batch(builder, {"alpha": np.array([0.0])}, tmp_path / "s.zarr", scheduler=address)
    assert e.value.field == "scheduler"
    assert not (tmp_path / "s.zarr").exists()
    sweep = _sweep(tmp_path)
    done = runner.invoke(
        app, ["run", str(sweep), "--scheduler", address, "--out", str(tmp_path / "out")]
    )
    assert done.exit_code == 2
    assert f"scheduler: no dask scheduler answered at '{address}': {why}" in _one_line(done.stderr)
