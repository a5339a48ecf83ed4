"""The console is a door with a lock: a served console refuses requests without its
secret, with a foreign ``Host`` (DNS rebinding) or a foreign ``Origin`` (a cross-site
page), on the page and on its socket alike, and forbids framing."""

from __future__ import annotations

import asyncio
import subprocess
import time
from collections.abc import Iterator
from urllib.parse import urlsplit

import httpx
import pytest

from mrcomm.console.guard import COOKIE, ConsoleGuard
from tests import needs
from tests.conftest import S1_PATH

needs.module("nicegui", extra="console")

from tests.console.chromium import console_url, free_port, mrcomm_process  # noqa: E402 (after the skip for a missing package)

SOCKET = "/_nicegui_ws/socket.io/?EIO=4&transport=polling"


def scope(host: str = "127.0.0.1:8080", query: str = "", **headers: str) -> dict[str, object]:
    raw = [(b"host", host.encode())] + [
        (k.replace("_", "-").encode(), v.encode()) for k, v in headers.items()
    ]
    return {"type": "http", "headers": raw, "query_string": query.encode()}


def test_the_guard_judges_host_origin_and_secret() -> None:
    guard = ConsoleGuard(8080, "s3cret")
    assert guard.url == "http://127.0.0.1:8080/?token=s3cret"
    assert guard.refusal(scope(query="token=s3cret")) == ("", True)
    assert guard.refusal(scope("localhost:8080", cookie=f"{COOKIE}=s3cret")) == ("", False)
    assert guard.refusal(scope())[0] == "missing token"
    assert guard.refusal(scope(query="token=guess"))[0] == "missing token"
    assert guard.refusal(scope(cookie=f"{COOKIE}=guess"))[0] == "missing token"
    assert guard.refusal(scope(cookie='"unbalanced'))[0] == "missing token"
    # DNS rebinding: the attacker's name resolves to 127.0.0.1, the Host header is his.
    assert guard.refusal(scope("evil.example:8080", query="token=s3cret"))[0] == "foreign host"
    assert guard.refusal(scope("127.0.0.1:9999", query="token=s3cret"))[0] == "foreign host"
    foreign = scope(query="token=s3cret", origin="http://evil.example")
    assert guard.refusal(foreign)[0] == "foreign origin"
    same = scope(query="token=s3cret", origin="http://localhost:8080")
    assert guard.refusal(same) == ("", True)
    assert ConsoleGuard(8080).token != ConsoleGuard(8080).token  # a new secret per run


@pytest.fixture(scope="module")
def console() -> Iterator[tuple[str, subprocess.Popen[str]]]:
    port = free_port("127.0.0.1")
    proc = mrcomm_process("run", str(S1_PATH), "--console", "--port", str(port), "--speed", "1")
    try:
        url = console_url(proc)
        deadline = time.monotonic() + 60
        while True:
            try:
                if httpx.get(url, timeout=2).status_code == 200:
                    break
            except httpx.HTTPError:
                pass
            assert time.monotonic() < deadline, "the console did not answer"
            assert proc.poll() is None
            time.sleep(0.2)  # polling a server that is starting, with a deadline
        yield url, proc
    finally:
        proc.kill()
        proc.communicate(timeout=30)


def test_the_page_needs_the_secret_and_forbids_framing(
    console: tuple[str, subprocess.Popen[str]],
) -> None:
    url, _ = console
    parts = urlsplit(url)
    base = f"{parts.scheme}://{parts.netloc}"
    page = httpx.get(url)
    assert page.status_code == 200
    assert page.headers["content-security-policy"] == "frame-ancestors 'none'"
    assert page.headers["x-frame-options"] == "DENY"
    assert page.headers["referrer-policy"] == "no-referrer"
    cookie = page.cookies[COOKIE]
    assert "httponly" in page.headers["set-cookie"].lower()
    assert "samesite=strict" in page.headers["set-cookie"].lower()
    assert httpx.get(f"{base}/", cookies={COOKIE: cookie}).status_code == 200
    bare = httpx.get(f"{base}/")
    assert bare.status_code == 403 and "missing token" in bare.text
    assert httpx.get(f"{base}/?token=guess").status_code == 403
    rebound = httpx.get(url, headers={"Host": f"evil.example:{parts.port}"})
    assert rebound.status_code == 403 and "foreign host" in rebound.text


def test_the_socket_refuses_foreign_pages(console: tuple[str, subprocess.Popen[str]]) -> None:
    url, _ = console
    parts = urlsplit(url)
    base = f"{parts.scheme}://{parts.netloc}"
    cookie = httpx.get(url).cookies[COOKIE]
    own = httpx.get(base + SOCKET, cookies={COOKIE: cookie}, headers={"Origin": base})
    assert own.status_code == 200 and own.text.startswith("0")  # the socket.io handshake
    evil = httpx.get(
        base + SOCKET, cookies={COOKIE: cookie}, headers={"Origin": "http://evil.example"}
    )
    assert evil.status_code == 403 and "foreign origin" in evil.text
    assert httpx.get(base + SOCKET).status_code == 403  # another local user: no secret

    import websockets

    async def connect(origin: str) -> str:
        target = f"ws://{parts.netloc}{SOCKET.replace('polling', 'websocket')}"
        try:
            async with websockets.connect(
                target, origin=origin, additional_headers={"Cookie": f"{COOKIE}={cookie}"}
            ) as socket:
                return str(await asyncio.wait_for(socket.recv(), 10))
        except Exception as err:  # refused at the handshake
            return f"refused: {type(err).__name__}"

    assert asyncio.run(connect(base)).startswith("0")  # engine.io's open packet
    assert asyncio.run(connect("http://evil.example")).startswith("refused")


def test_only_a_few_page_sockets_at_once(console: tuple[str, subprocess.Popen[str]]) -> None:
    """Each page socket holds a page's state in the process: an authenticated client
    opening sockets in a loop is held to MAX_SOCKETS of them."""
    import websockets

    from mrcomm.console.guard import MAX_SOCKETS

    url, _ = console
    parts = urlsplit(url)
    base = f"{parts.scheme}://{parts.netloc}"
    cookie = httpx.get(url).cookies[COOKIE]
    target = f"ws://{parts.netloc}{SOCKET.replace('polling', 'websocket')}"

    async def flood() -> tuple[int, int]:
        opened, refused = [], 0
        try:
            for _ in range(MAX_SOCKETS + 4):
                try:
                    socket = await websockets.connect(
                        target, origin=base, additional_headers={"Cookie": f"{COOKIE}={cookie}"}
                    )
                    await asyncio.wait_for(socket.recv(), 10)  # served: the open packet
                    opened.append(socket)
                except Exception:
                    refused += 1
            return len(opened), refused
        finally:
            for socket in opened:
                await socket.close()

    opened, refused = asyncio.run(flood())
    assert opened <= MAX_SOCKETS and refused >= 4, (opened, refused)
