"""``--dask tcp://HOST:PORT`` where no Dask scheduler listens: one message naming the
address, exit status 2, within seconds (never a hang, never a traceback)."""

from __future__ import annotations

import http.server
import socket
import threading
import time
from collections.abc import Iterator
from pathlib import Path

import pytest
import yaml

from mresim_phys.cli import main
from mresim_phys.sweeps import dask_connect

REPO = Path(__file__).resolve().parent.parent
QUICKSTART = REPO / "scenarios" / "01_quickstart.yaml"


@pytest.fixture
def study(tmp_path: Path) -> Path:
    """A study of one quickstart run."""
    path = tmp_path / "study.yaml"
    data = {"name": "t", "scenarios": [str(QUICKSTART)], "seeds": 1, "steps": 5}
    path.write_text(yaml.safe_dump(data), encoding="utf-8")
    return path


@pytest.fixture
def silent() -> Iterator[str]:
    """A listener that accepts connections and says nothing."""
    with socket.socket() as server:
        server.bind(("127.0.0.1", 0))
        server.listen(8)
        yield f"tcp://127.0.0.1:{server.getsockname()[1]}"


@pytest.fixture
def web() -> Iterator[str]:
    """A tiny HTTP server (as the Dask dashboard is)."""
    server = http.server.ThreadingHTTPServer(("127.0.0.1", 0), http.server.SimpleHTTPRequestHandler)
    thread = threading.Thread(target=server.serve_forever, daemon=True)
    thread.start()
    yield f"tcp://127.0.0.1:{server.server_address[1]}"
    server.shutdown()
    server.server_close()


@pytest.fixture
def talker() -> Iterator[str]:
    """A server that greets with text (an SSH or SMTP server, say)."""
    server = socket.socket()
    server.bind(("127.0.0.1", 0))
    server.listen(8)

    def serve() -> None:
        while True:
            try:
                conn, _ = server.accept()
            except OSError:
                return
            with conn:
                conn.sendall(b"SSH-2.0-OpenSSH_9.6\r\n")

    threading.Thread(target=serve, daemon=True).start()
    yield f"tcp://127.0.0.1:{server.getsockname()[1]}"
    server.close()


def refused_port() -> str:
    """An address where nothing listens."""
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        return f"tcp://127.0.0.1:{probe.getsockname()[1]}"


@pytest.mark.parametrize(
    ("server", "says"),
    [
        ("silent", "sent no Dask greeting within 1 s"),
        ("web", "sent no Dask greeting within 1 s"),
        ("talker", "is not a Dask scheduler (it answered b'SSH-2.0-'"),
        ("refused", "cannot connect to 127.0.0.1:"),
    ],
)
def test_no_scheduler_at_the_address_is_a_clear_error(
    server: str,
    says: str,
    study: Path,
    tmp_path: Path,
    request: pytest.FixtureRequest,
    monkeypatch: pytest.MonkeyPatch,
    capsys: pytest.CaptureFixture[str],
) -> None:
    monkeypatch.setattr(dask_connect, "CONNECT_TIMEOUT", 1.0)
    address = refused_port() if server == "refused" else request.getfixturevalue(server)
    out = tmp_path / "out"
    started = time.monotonic()
    code = main(["sweep", str(study), "--out", str(out), "--dask", address])
    assert time.monotonic() - started < 10
    err = capsys.readouterr().err
    assert code == 2 and f"--dask {address}: no Dask scheduler answered: " in err, err
    assert says in err, err
    assert "Traceback" not in err and err.count("\n") == 1  # one paragraph
    assert not out.exists()  # nothing written


def test_a_real_scheduler_is_joined() -> None:
    from distributed import Client, LocalCluster

    with LocalCluster(
        n_workers=0, processes=False, dashboard_address=None, scheduler_port=0, protocol="tcp"
    ) as cluster:
        client = dask_connect.connect(Client, cluster.scheduler_address)
        assert client.status == "running"
        client.close()
