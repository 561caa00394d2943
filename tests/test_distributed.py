"""Sweeps on a dask.distributed cluster: a real scheduler and worker processes on this machine."""

from __future__ import annotations

import json

import pytest

from wetclutch import cli
from wetclutch.errors import WetclutchError
from wetclutch.launch import design as designs
from wetclutch.launch import distributed, verify
from wetclutch.params import Params


@pytest.fixture(scope="module")
def cluster():
    from distributed import LocalCluster

    with LocalCluster(processes=True, n_workers=2, threads_per_worker=1, host="127.0.0.1",
                      dashboard_address=None) as c:
        yield c


def test_scheduler_from_option_or_environment(monkeypatch):
    monkeypatch.delenv(distributed.ENV_SCHEDULER, raising=False)
    assert distributed.scheduler_address(None) is None
    monkeypatch.setenv(distributed.ENV_SCHEDULER, "tcp://10.1.2.3:8786")
    assert distributed.scheduler_address(None) == "tcp://10.1.2.3:8786"
    assert distributed.scheduler_address("tcp://127.0.0.1:1") == "tcp://127.0.0.1:1"


def test_split_keeps_order_and_covers_every_item():
    items = list(range(11))
    for n in (1, 2, 3, 4, 11, 20):
        parts = distributed.split(items, n)
        assert len(parts) <= n
        assert [x for p in parts for x in p] == items


def test_map_batches_returns_results_in_item_order(cluster):
    items = list(range(23))
    out = distributed.map_batches(abs, [-x for x in items], cluster.scheduler_address, batch_size=4)
    assert out == items


def test_verify_on_the_cluster_equals_the_local_run(cluster):
    # a few launches (corners off): the same verify.json bit for bit, local processes or the cluster
    d = designs.cached(Params())
    local = verify.run(d, n=3, seed=7, workers=1, corners=False, progress=False)
    remote = verify.run(d, n=3, seed=7, corners=False, progress=False, scheduler=cluster.scheduler_address)
    assert json.dumps(remote, sort_keys=True) == json.dumps(local, sort_keys=True)
    assert remote["cases"] == 3


def test_verify_honours_the_environment(cluster, monkeypatch):
    monkeypatch.setenv(distributed.ENV_SCHEDULER, cluster.scheduler_address)
    d = designs.cached(Params())
    local = verify.run(d, n=1, seed=11, workers=1, corners=False, progress=False, scheduler="")
    remote = verify.run(d, n=1, seed=11, corners=False, progress=False)
    assert json.dumps(remote, sort_keys=True) == json.dumps(local, sort_keys=True)


def test_unreachable_scheduler_is_a_one_line_error(tmp_path, capsys, monkeypatch):
    monkeypatch.setattr(distributed, "CONNECT_TIMEOUT_S", 2)
    with pytest.raises(WetclutchError, match="cannot reach a dask scheduler"):
        distributed.connect("tcp://127.0.0.1:9")
    code = cli.main(["verify", "--out", str(tmp_path / "v"), "--samples", "1", "--quiet",
                     "--scheduler", "tcp://127.0.0.1:9"])
    err = capsys.readouterr().err
    assert code == 2
    assert err.startswith("wetclutch: error: --scheduler") and err.count("\n") == 1


def test_a_server_that_is_no_dask_scheduler_is_a_one_line_error_not_a_hang(monkeypatch):
    # a web server accepts the connection and waits for a request: the dask client would wait for its handshake
    # past its own timeout (a verification hung for minutes)
    import socket
    import threading

    monkeypatch.setattr(distributed, "CONNECT_TIMEOUT_S", 1)
    server = socket.create_server(("127.0.0.1", 0))
    port = server.getsockname()[1]
    accepted = []
    threading.Thread(target=lambda: accepted.append(server.accept()), daemon=True).start()
    try:
        with pytest.raises(WetclutchError, match="no dask scheduler answers at .* sent no dask handshake"):
            distributed.connect(f"tcp://127.0.0.1:{port}", "--scheduler")
    finally:
        for conn, _ in accepted:
            conn.close()
        server.close()
