"""Monte Carlo trials on a Dask cluster: the report of a local run with the same seed.

A ``LocalCluster`` of two single-threaded worker processes runs the trials of the seed's search
listing; every trial's run (outcome, line, message, time to the last bit, statements) and the
summary must equal a run in this process, since a trial depends only on (program, task, seed,
index) (:mod:`synth.replay.run`). Dask is the ``dask`` extra, which ``make test`` installs.
"""

from __future__ import annotations

from collections.abc import Iterator
from typing import Any

import distributed
import pytest
from _paths import SEED_SEARCH, SEED_TASK

from synth.cli import main
from synth.replay import cluster, replay_program


@pytest.fixture(scope="module")
def client() -> Iterator[Any]:
    cluster = distributed.LocalCluster(
        n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None
    )
    with distributed.Client(cluster) as c:
        yield c
    cluster.close()


def test_a_cluster_gives_the_local_report(client: Any) -> None:
    text = SEED_SEARCH.read_text(encoding="utf-8")
    # 20 trials of seed 0 include trial 18, the listing's abort beside the box
    on_cluster = replay_program(text, SEED_TASK, trials=20, seed=0, client=client)
    local = replay_program(text, SEED_TASK, trials=20, seed=0, workers=1)
    assert on_cluster.trials == local.trials
    assert on_cluster.monte_carlo == local.monte_carlo
    assert dict(local.monte_carlo.outcomes) == {"success": 19, "abort": 1}


def test_an_unreachable_scheduler_is_a_usage_error(
    capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    # Nothing listens on port 9 (discard): Dask retries until its timeout, which is only waited.
    monkeypatch.setattr(cluster, "CONNECT_TIMEOUT_S", 0.5)
    argv = ["replay", str(SEED_SEARCH), "--task", str(SEED_TASK), "--trials", "2"]
    assert main([*argv, "--dask", "tcp://127.0.0.1:9"]) == 2
    assert "--dask tcp://127.0.0.1:9: cannot reach the scheduler" in capsys.readouterr().err


class _SlowToClose:
    """A client or cluster whose close times out, as a loaded machine's may after Ctrl-C."""

    def __init__(self) -> None:
        self.asked = 0

    def close(self) -> None:
        self.asked += 1
        raise TimeoutError("timed out after 30 s")


def test_a_close_that_times_out_is_a_warning_not_an_internal_error(
    caplog: pytest.LogCaptureFixture,
) -> None:
    client, local = _SlowToClose(), _SlowToClose()
    cluster._close(client, local)
    # both were asked (the cluster too, after the client failed) and each failure said once
    assert (client.asked, local.asked) == (1, 1)
    said = [r.getMessage() for r in caplog.records]
    assert said == [
        "the Dask client did not close cleanly (TimeoutError: timed out after 30 s)",
        "the Dask local cluster did not close cleanly (TimeoutError: timed out after 30 s)",
    ]


@pytest.mark.parametrize("address", ["bogus", "", "tcp://", "foo://x:1", "tcp://[::1"])
def test_a_malformed_scheduler_address_is_a_usage_error(
    address: str, capsys: pytest.CaptureFixture[str]
) -> None:
    # distributed's address parser raises ValueError: that was exit 70, an internal error
    argv = ["replay", str(SEED_SEARCH), "--task", str(SEED_TASK), "--trials", "2"]
    assert main([*argv, "--dask", address]) == 2
    err = capsys.readouterr().err
    assert err.startswith(f"synth replay: error: --dask {address!r}: not a scheduler address (")
    assert err.rstrip().endswith("write HOST:PORT, tcp://HOST:PORT, or local")
