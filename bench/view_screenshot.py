"""Rerun's web viewer on an ``.rrd``, screenshot by headless Chromium once it has drawn it.

Run: ``.venv/bin/python bench/view_screenshot.py FILE.rrd OUT.png [--timeout S]``. Serves the
file with the viewer that came with rerun-sdk (``rerun --web-viewer``, on free ports), opens it in
headless Chromium (Debian's ``chromium``; WebGL by SwiftShader, which the viewer shows as
"Software rasterizer") and takes a screenshot every 2 s over Chromium's DevTools protocol until
the page is no longer Rerun's loading screen and two captures in a row are the same picture (the
recording drawn and settled), at most ``--timeout`` seconds (default 300). Prints one line per
state it sees. Exit 0 with the screenshot written; 1 (one line) when the viewer never drew within
the bound; 0 and a line "skipped" without chromium. Made docs/view.png.

Why not ``chromium --screenshot --virtual-time-budget``: virtual time runs on while the viewer's
WebAssembly compiles off the page's thread, so on a loaded machine the picture is the loading
screen ("Loading Application Bundle... 100%"), however long the budget.
"""

from __future__ import annotations

import argparse
import base64
import contextlib
import io
import json
import os
import shutil
import signal
import socket
import struct
import subprocess
import sys
import tempfile
import time
import urllib.request
from collections.abc import Iterator
from pathlib import Path

import numpy as np
from common import shared

from a1_leg_fk.cli.rerun_sdk import viewer_executable

PAGE = (1400, 800)
"""The page's size [px] (width, height)."""
EVERY_S = 2.0
"""Seconds between two screenshots."""
SATURATED = 0.25
"""A pixel is coloured when its channels span more than this share of full scale: the loading
screen and the viewer's own chrome are grey (white, black, greys), plot lines and the robot not."""
DRAWN_SHARE = 0.01
"""The share of coloured pixels a drawn recording has at least: 0 on the loading screen, 0.6 % on
the viewer before the recording's entities come (its own blue, orange and red marks), 1.2-1.5 %
on the test's 2 s walk drawn (3.5 % while only its 3D view is in)."""
SETTLED = 3
"""Equal screenshots in a row (2 s apart) that end the wait: while the recording streams in, the
viewer's layout changes and it shows the stream's latency."""
CHROMIUM_FLAGS = [
    "--headless=new", "--no-sandbox", "--ignore-gpu-blocklist", "--enable-webgl",
    "--use-angle=swiftshader", "--enable-unsafe-swiftshader", "--disable-background-networking",
    "--disable-component-update", "--disable-sync", "--no-first-run", "--hide-scrollbars",
    "--remote-debugging-port=0",
]  # fmt: skip


def pixels(png: bytes) -> np.ndarray:
    """(H, W, 3) RGB floats in [0, 1] of a PNG."""
    from PIL import Image

    with Image.open(io.BytesIO(png)) as image:
        return np.asarray(image.convert("RGB"), dtype=np.float64) / 255.0


def coloured_share(image: np.ndarray) -> float:
    """The share of pixels whose channels span more than :data:`SATURATED`."""
    return float((image.max(axis=2) - image.min(axis=2) > SATURATED).mean())


class DevTools:
    """A client of one page's DevTools websocket (RFC 6455, text frames, client-masked)."""

    def __init__(self, url: str) -> None:
        host_port, path = url.removeprefix("ws://").split("/", 1)
        host, port = host_port.rsplit(":", 1)
        self.sock = socket.create_connection((host, int(port)), 120.0)
        key = base64.b64encode(os.urandom(16)).decode()
        self.sock.sendall(
            f"GET /{path} HTTP/1.1\r\nHost: {host_port}\r\nUpgrade: websocket\r\n"
            f"Connection: Upgrade\r\nSec-WebSocket-Key: {key}\r\nSec-WebSocket-Version: 13\r\n\r\n"
            .encode()
        )  # fmt: skip
        reply = b""
        while b"\r\n\r\n" not in reply:
            reply += self._exactly(1)
        if b" 101 " not in reply.split(b"\r\n", 1)[0]:
            raise ConnectionError(f"DevTools refused the websocket: {reply[:80]!r}")
        self.last_id = 0

    def close(self) -> None:
        """Close the websocket's connection."""
        self.sock.close()

    def _exactly(self, count: int) -> bytes:
        data = b""
        while len(data) < count:
            chunk = self.sock.recv(count - len(data))
            if not chunk:
                raise ConnectionError("DevTools closed the websocket")
            data += chunk
        return data

    def _send(self, opcode: int, payload: bytes) -> None:
        size = len(payload)
        header = bytes([0x80 | opcode])
        if size < 126:
            header += bytes([0x80 | size])
        elif size < 1 << 16:
            header += bytes([0x80 | 126]) + struct.pack("!H", size)
        else:
            header += bytes([0x80 | 127]) + struct.pack("!Q", size)
        mask = os.urandom(4)
        masked = np.frombuffer(payload, np.uint8) ^ np.resize(np.frombuffer(mask, np.uint8), size)
        self.sock.sendall(header + mask + masked.tobytes())

    def _message(self) -> bytes:
        """The next text message (its frames joined), answering pings on the way."""
        message = b""
        while True:
            first, second = self._exactly(2)
            size = second & 0x7F
            if size == 126:
                size = struct.unpack("!H", self._exactly(2))[0]
            elif size == 127:
                size = struct.unpack("!Q", self._exactly(8))[0]
            payload = self._exactly(size)
            opcode = first & 0x0F
            if opcode == 0x8:
                raise ConnectionError("DevTools closed the websocket")
            if opcode == 0x9:
                self._send(0xA, payload)
                continue
            message += payload
            if first & 0x80:
                return message

    def call(self, method: str, **params: object) -> dict[str, object]:
        """``method``'s result; ``RuntimeError`` with DevTools' error."""
        self.last_id += 1
        self._send(
            0x1, json.dumps({"id": self.last_id, "method": method, "params": params}).encode()
        )
        while True:
            answer = json.loads(self._message())
            if answer.get("id") == self.last_id:
                if "error" in answer:
                    raise RuntimeError(f"{method}: {answer['error']}")
                result: dict[str, object] = answer["result"]
                return result

    def screenshot(self) -> bytes:
        """The page as a PNG."""
        return base64.b64decode(str(self.call("Page.captureScreenshot", format="png")["data"]))


@contextlib.contextmanager
def started(command: list[str], **options: object) -> Iterator[subprocess.Popen[bytes]]:
    """``command`` in a session of its own, its output dropped; its group ended on leaving."""
    process = subprocess.Popen(  # type: ignore[call-overload]
        command, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, start_new_session=True,
        **options,
    )  # fmt: skip
    try:
        yield process
    finally:
        with contextlib.suppress(ProcessLookupError):
            os.killpg(process.pid, signal.SIGTERM)
        try:
            process.wait(10)
        except subprocess.TimeoutExpired:
            os.killpg(process.pid, signal.SIGKILL)
            process.wait()


def page_socket(profile: Path) -> str:
    """The DevTools websocket of the page Chromium opened with ``profile``."""
    active = profile / "DevToolsActivePort"
    if not shared.wait_for(lambda: active.is_file() and len(active.read_text().split()) == 2, 60):
        raise TimeoutError("Chromium's DevTools did not open within 60 s")
    port = active.read_text().split()[0]
    with urllib.request.urlopen(f"http://127.0.0.1:{port}/json/list", timeout=30) as reply:
        targets = json.load(reply)
    return str(next(t["webSocketDebuggerUrl"] for t in targets if t["type"] == "page"))


def settled_screenshot(page: DevTools, timeout_s: float) -> bytes:
    """The first screenshot that shows a drawn recording (:data:`DRAWN_SHARE`) and equals the
    :data:`SETTLED` - 1 before it, taken every :data:`EVERY_S`; ``TimeoutError`` after
    ``timeout_s``."""
    started_at, previous, state, same = time.monotonic(), b"", "", 0
    while time.monotonic() - started_at < timeout_s:
        time.sleep(EVERY_S)
        png = page.screenshot()
        share = coloured_share(pixels(png))
        now = "drawn" if share >= DRAWN_SHARE else "loading"
        if now != state:
            elapsed = time.monotonic() - started_at
            print(f"view_screenshot: {now} at {elapsed:.0f} s ({100 * share:.2f} % coloured)")
            state = now
        same = same + 1 if png == previous else 1
        if now == "drawn" and same >= SETTLED:
            return png
        previous = png
    raise TimeoutError(f"the viewer did not draw the recording within {timeout_s:.0f} s")


def screenshot(rrd: Path, out: Path, timeout_s: float) -> None:
    """Serve ``rrd`` in Rerun's web viewer and write its settled screenshot to ``out``."""
    viewer = viewer_executable()
    if viewer is None:
        raise FileNotFoundError("rerun-sdk's viewer binary (pip install 'a1_leg_fk[view]')")
    web, grpc = shared.free_port(), shared.free_port()
    serve = [viewer, "--web-viewer", "--web-viewer-port", str(web), "--port", str(grpc), str(rrd)]
    environment = {**os.environ, "RERUN_ANALYTICS": "0"}
    with (
        started(serve, env=environment),
        tempfile.TemporaryDirectory(ignore_cleanup_errors=True) as profile,
    ):
        if not shared.wait_for(lambda: shared.listening(web) and shared.listening(grpc), 60):
            raise TimeoutError("the web viewer did not listen within 60 s")
        browser = ["chromium", *CHROMIUM_FLAGS, f"--user-data-dir={profile}", "about:blank"]
        with started(browser), contextlib.closing(DevTools(page_socket(Path(profile)))) as page:
            page.call("Page.enable")
            width, height = PAGE
            metrics = {"width": width, "height": height, "deviceScaleFactor": 1, "mobile": False}
            page.call("Emulation.setDeviceMetricsOverride", **metrics)
            url = f"http://127.0.0.1:{web}/?url=rerun%2Bhttp%3A%2F%2F127.0.0.1%3A{grpc}%2Fproxy"
            page.call("Page.navigate", url=url)
            out.write_bytes(settled_screenshot(page, timeout_s))
    print(f"view_screenshot: wrote {out}")


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("rrd", type=Path)
    parser.add_argument("out", type=Path)
    parser.add_argument("--timeout", type=float, default=300.0, help="seconds, at most")
    options = parser.parse_args()
    if shutil.which("chromium") is None:
        print("view_screenshot: no chromium, skipped")
        return 0
    if not options.rrd.is_file():
        print(f"view_screenshot: {options.rrd}: no such file", file=sys.stderr)
        return 2
    try:
        screenshot(options.rrd, options.out, options.timeout)
    except (OSError, TimeoutError, RuntimeError) as error:
        print(f"view_screenshot: {error}", file=sys.stderr)
        return 1
    except KeyboardInterrupt:
        return 130
    return 0


if __name__ == "__main__":
    sys.exit(main())
