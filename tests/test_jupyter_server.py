"""The student's tools: a Jupyter server opens the jupytext notebooks as notebooks and runs a cell.

Starts ``jupyter server`` on a free local port with a token, reads two notebooks through the
contents API (jupytext serves the ``.py`` files with ``type=notebook``), starts the kernel the
notebooks name, runs one cell over the kernel's websocket, and always stops the server.
"""

from __future__ import annotations

import json
import os
import pathlib
import secrets
import shutil
import socket
import subprocess
import sys
import time
import urllib.request
import uuid

import pytest
import websocket
from conftest import NOTEBOOK_KERNEL, jupyter_command, stop_server

ROOT = pathlib.Path(__file__).resolve().parents[1]
OPENED = ("notebooks/01_crawler_odometry.py", "notebooks/06_one_point_ransac.py")
START_TIMEOUT_S = 120
REPLY_TIMEOUT_S = 120


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


class Server:
    """A running ``jupyter server``: its base URL and token, and a small REST client."""

    def __init__(self, base: str, token: str):
        self.base, self.token = base, token

    def call(self, path: str, method: str = "GET", body: dict | None = None) -> dict:
        request = urllib.request.Request(
            f"{self.base}{path}",
            method=method,
            data=None if body is None else json.dumps(body).encode(),
            headers={"Authorization": f"token {self.token}", "Content-Type": "application/json"},
        )
        with urllib.request.urlopen(request, timeout=60) as response:
            text = response.read()
        return json.loads(text) if text else {}


@pytest.fixture
def server(tmp_path):
    port, token = free_port(), secrets.token_hex(16)
    log = (tmp_path / "server.log").open("w")
    proc = subprocess.Popen(
        [
            *jupyter_command("server", port, token),
            f"--ServerApp.root_dir={ROOT}",
        ],
        stdout=log,
        stderr=subprocess.STDOUT,
        env={**os.environ, "JUPYTER_RUNTIME_DIR": str(tmp_path / "runtime")},
    )
    running = Server(f"http://127.0.0.1:{port}", token)
    try:
        deadline = time.monotonic() + START_TIMEOUT_S
        while True:
            try:
                running.call("/api/status")
                break
            except OSError:
                if proc.poll() is not None or time.monotonic() > deadline:
                    log.flush()
                    pytest.fail(
                        "jupyter server did not start:\n" + (tmp_path / "server.log").read_text()[-3000:]
                    )
                time.sleep(0.5)
        yield running
    finally:
        stop_server(proc, log)


def execute(server: Server, kernel_id: str, code: str) -> str:
    """Run ``code`` in the kernel over its websocket; return its stdout (raise on an error reply)."""
    ws = websocket.create_connection(
        f"{server.base.replace('http', 'ws', 1)}/api/kernels/{kernel_id}/channels?token={server.token}",
        timeout=REPLY_TIMEOUT_S,
    )
    try:
        msg_id = uuid.uuid4().hex
        ws.send(
            json.dumps(
                {
                    "header": {
                        "msg_id": msg_id,
                        "msg_type": "execute_request",
                        "username": "test",
                        "session": uuid.uuid4().hex,
                        "version": "5.3",
                    },
                    "parent_header": {},
                    "metadata": {},
                    "content": {"code": code, "silent": False, "store_history": False},
                    "channel": "shell",
                }
            )
        )
        stdout, deadline = [], time.monotonic() + REPLY_TIMEOUT_S
        while time.monotonic() < deadline:
            msg = json.loads(ws.recv())
            if msg.get("parent_header", {}).get("msg_id") != msg_id:
                continue
            if msg["msg_type"] == "stream":
                stdout.append(msg["content"]["text"])
            if msg["msg_type"] == "error":
                raise AssertionError("\n".join(msg["content"]["traceback"]))
            if msg["msg_type"] == "execute_reply":
                assert msg["content"]["status"] == "ok", msg["content"]
                return "".join(stdout)
        raise AssertionError(f"no reply within {REPLY_TIMEOUT_S} s")
    finally:
        ws.close()


@pytest.mark.notebook
def test_server_opens_jupytext_notebooks_and_runs_a_cell(server):
    for path in OPENED:
        model = server.call(f"/api/contents/{path}?type=notebook&content=1")
        assert model["type"] == "notebook", f"{path} opened as {model['type']}"
        cells = model["content"]["cells"]
        assert len(cells) > 10 and cells[0]["cell_type"] == "markdown"
        assert model["content"]["metadata"]["kernelspec"]["name"] == NOTEBOOK_KERNEL
    notebook = server.call(f"/api/contents/{OPENED[0]}?type=notebook&content=1")["content"]
    first_code = next(c for c in notebook["cells"] if c["cell_type"] == "code")
    kernel = server.call("/api/kernels", "POST", {"name": NOTEBOOK_KERNEL, "path": "notebooks"})
    try:
        out = execute(server, kernel["id"], "".join(first_code["source"]) + "\nprint('seeded', SEED)")
        assert out.strip().endswith("seeded 1"), out
    finally:
        server.call(f"/api/kernels/{kernel['id']}", "DELETE")


@pytest.mark.parametrize("root", ["", "notebooks"], ids=["served-from-repository", "served-from-notebooks"])
def test_saving_from_jupyterlab_leaves_every_notebook_unchanged(root, tmp_path):
    """Whichever folder JupyterLab serves, jupytext finds notebooks/jupytext.toml, and a notebook
    saved as JupyterLab saves it (the kernel's display name and language_info added to the
    metadata by the running kernel) is written back byte for byte as it was."""
    from jupytext.sync_contentsmanager import TextFileContentsManager

    copy = tmp_path / "repo"
    (copy / "notebooks").mkdir(parents=True)
    shutil.copy2(ROOT / "notebooks" / "jupytext.toml", copy / "notebooks" / "jupytext.toml")
    manager = TextFileContentsManager(root_dir=str(copy / root))
    for path in sorted((ROOT / "notebooks").glob("[0-9][0-9]_*.py")):
        shutil.copy2(path, copy / "notebooks" / path.name)
        name = path.name if root == "notebooks" else f"notebooks/{path.name}"
        model = manager.get(name)
        assert model["type"] == "notebook"
        metadata = model["content"]["metadata"]
        metadata["kernelspec"] = {
            "display_name": "Python 3 (ipykernel)",
            "language": "python",
            "name": "python3",
        }
        metadata["language_info"] = {"name": "python", "version": sys.version.split()[0]}
        manager.save(model, name)
        assert (copy / "notebooks" / path.name).read_bytes() == path.read_bytes(), f"saving rewrote {name}"
