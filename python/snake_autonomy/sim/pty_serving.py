"""Serving a mocked bus on a pseudo-terminal, with its control socket (see mock_servo_bus.py).

PtyServing is the half of MockServoBus that owns the pty, the serving loop, the thread and the
control socket (a Unix socket, one JSON object per line, answered by one JSON line); the class
that mixes it in provides ``handle(bytes, latest_only) -> bytes``, ``_clear_input()``,
``_late_dropped()``, ``_lock`` and the
methods CONTROL_COMMANDS call. MockBusClient talks to the control socket of a running mock.
"""
import json
import os
import select
import selectors
import socket
import threading
import tty


class PtyServing:
    """Serves ``self.handle`` on a pty (see the module docstring)."""

    def __init__(self):
        self._master = self._slave = None
        self.link = None
        self._wake_r, self._wake_w = os.pipe()
        self._stop = threading.Event()
        self._thread = None
        self._control_path = None
        self._control_sock = None

    def open_pty(self, link: str) -> str:
        """Creates the pty and the symlink `link` to its slave; returns the slave's path."""
        with self._lock:
            self._close_pty_locked()
            master, slave = os.openpty()
            tty.setraw(slave)  # no echo or translation before a client configures the port
            os.set_blocking(master, False)
            path = os.ttyname(slave)
            tmp = f"{link}.tmp{os.getpid()}"
            if os.path.lexists(tmp):
                os.unlink(tmp)
            os.symlink(path, tmp)
            os.replace(tmp, link)
            # The slave stays open: reads on the master fail with EIO while no slave is open, and
            # ROBOTIS's SDK closes and reopens the port when it sets the baud rate.
            self._master, self._slave, self.link = master, slave, link
            self._clear_input()
        self._wake()
        return path

    def close_pty(self):
        """The pty closing: clients get EIO/hang-up; the symlink is removed."""
        with self._lock:
            self._close_pty_locked()
        self._wake()

    def reopen_pty(self) -> str:
        if self.link is None:
            raise RuntimeError("reopen_pty: the pty was never opened")
        return self.open_pty(self.link)

    def _close_pty_locked(self):
        for fd in (self._master, self._slave):
            if fd is not None:
                os.close(fd)
        self._master = self._slave = None
        if self.link and os.path.islink(self.link):
            os.unlink(self.link)

    def _wake(self):
        try:
            os.write(self._wake_w, b"x")
        except OSError:
            pass

    def listen_control(self, path: str):
        """Serves the control socket at `path` (see CONTROL_COMMANDS) from the serving loop."""
        if os.path.lexists(path):
            os.unlink(path)
        sock = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
        sock.bind(path)
        sock.listen(4)
        sock.setblocking(False)
        self._control_sock, self._control_path = sock, path
        self._wake()

    def serve_forever(self, on_ready=None):
        """Serves packets (and the control socket) until stop(). on_ready() once it accepts packets."""
        sel = selectors.DefaultSelector()
        sel.register(self._wake_r, selectors.EVENT_READ, "wake")
        registered_master = None
        control_registered = False
        clients = {}
        ready_sent = False
        try:
            while not self._stop.is_set():
                if self._master != registered_master:
                    if registered_master is not None:
                        sel.unregister(registered_master)
                    registered_master = self._master
                    if registered_master is not None:
                        sel.register(registered_master, selectors.EVENT_READ, "pty")
                if self._control_sock is not None and not control_registered:
                    sel.register(self._control_sock, selectors.EVENT_READ, "listen")
                    control_registered = True
                if not ready_sent and registered_master is not None:
                    ready_sent = True
                    if on_ready:
                        on_ready()
                for key, _ in sel.select(timeout=0.5):
                    if key.data == "wake":
                        os.read(self._wake_r, 4096)
                    elif key.data == "pty":
                        self._serve_pty(key.fd)
                    elif key.data == "listen":
                        conn, _ = self._control_sock.accept()
                        conn.setblocking(False)
                        clients[conn] = bytearray()
                        sel.register(conn, selectors.EVENT_READ, "client")
                    elif key.data == "client":
                        if not self._serve_control(key.fileobj, clients):
                            sel.unregister(key.fileobj)
                            key.fileobj.close()
                            del clients[key.fileobj]
        finally:
            for conn in clients:
                conn.close()
            sel.close()

    def _serve_pty(self, fd):
        try:
            data = os.read(fd, 4096)
        except BlockingIOError:
            return
        except OSError:
            return  # closed underneath us (close_pty)
        reply = self.handle(data, latest_only=True)
        with self._lock:
            if reply and self._master == fd and self._input_waiting(fd):
                # The master sent its next packet while this reply was being made (this process was
                # slow, e.g. a loaded machine): it gave up on this one. A real servo answers within
                # its return delay or not at all, so the late reply is dropped, not sent into the
                # next transaction.
                self._late_dropped()
                return
            if reply and self._master == fd:
                try:
                    os.write(fd, reply)
                except OSError:
                    pass  # nobody reads (full buffer): the bytes are lost, as on a wire

    @staticmethod
    def _input_waiting(fd) -> bool:
        try:
            return bool(select.select([fd], [], [], 0)[0])
        except (OSError, ValueError):
            return False

    def _serve_control(self, conn, clients) -> bool:
        try:
            data = conn.recv(65536)
        except OSError:
            return False
        if not data:
            return False
        buf = clients[conn]
        buf += data
        while b"\n" in buf:
            line, _, rest = bytes(buf).partition(b"\n")
            buf[:] = rest
            try:
                conn.setblocking(True)
                conn.sendall((json.dumps(self.control(line.decode("utf-8", "replace"))) + "\n").encode())
                conn.setblocking(False)
            except OSError:
                return False  # the client went away: close it, keep serving
        return True

    def control(self, line: str) -> dict:
        """Runs one control command (JSON text); returns {"ok": true, ...} or {"ok": false, "error": ...}."""
        try:
            cmd = json.loads(line)
            if not isinstance(cmd, dict):
                raise ValueError(f"{line.strip()[:80]!r} is not a JSON object")
            name = cmd.pop("cmd")
            if not isinstance(name, str) or name not in CONTROL_COMMANDS:
                raise ValueError(f"cmd: {name!r} is not one of {sorted(CONTROL_COMMANDS)}")
            result = CONTROL_COMMANDS[name](self, **cmd)
            return {"ok": True, "result": result}
        except (ValueError, TypeError, KeyError, RuntimeError) as exc:
            return {"ok": False, "error": f"{type(exc).__name__}: {exc}"}
        except Exception as exc:  # noqa: BLE001 - a bad command must never end the serving loop
            return {"ok": False, "error": f"unexpected {type(exc).__name__}: {exc}"}

    def start(self, link: str, control_path: str = None):
        """Embedded use: opens the pty at `link` and serves it from a thread."""
        self.open_pty(link)
        if control_path:
            self.listen_control(control_path)
        ready = threading.Event()
        self._stop.clear()
        self._thread = threading.Thread(target=self.serve_forever, kwargs={"on_ready": ready.set},
                                        name="mock_servo_bus", daemon=True)
        self._thread.start()
        if not ready.wait(5.0):
            raise RuntimeError("mock servo bus did not start within 5 s")
        return self

    def request_stop(self):
        """Makes serve_forever return (safe from a signal handler)."""
        self._stop.set()
        self._wake()

    def stop(self):
        self._stop.set()
        self._wake()
        if self._thread is not None:
            self._thread.join(5.0)
            self._thread = None
        self.close_pty()
        if self._control_sock is not None:
            self._control_sock.close()
            if self._control_path and os.path.lexists(self._control_path):
                os.unlink(self._control_path)
            self._control_sock = None

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.stop()


CONTROL_COMMANDS = {
    "stats": lambda bus: bus.stats(),
    "reset_stats": lambda bus: bus.reset_stats(),
    "state": lambda bus: bus.state(),
    "inject": lambda bus, kind, ids=None, count=None: bus.inject(kind, ids, count),
    "set_silent": lambda bus, id, silent=True: bus.set_silent(id, silent),  # noqa: A006
    "set_hardware_error": lambda bus, id, bits: bus.set_hardware_error(id, bits),  # noqa: A006
    "clear_faults": lambda bus: bus.clear_faults(),
    "close_pty": lambda bus: bus.close_pty(),
    "reopen_pty": lambda bus: bus.reopen_pty(),
}


class MockBusClient:
    """Talks to a running mock's control socket: MockBusClient(path).call("stats")."""

    def __init__(self, path: str, timeout_s: float = 5.0):
        self._sock = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
        self._sock.settimeout(timeout_s)
        self._sock.connect(path)
        self._buf = b""

    def call(self, cmd: str, **kwargs):
        self._sock.sendall((json.dumps({"cmd": cmd, **kwargs}) + "\n").encode())
        while b"\n" not in self._buf:
            chunk = self._sock.recv(65536)
            if not chunk:
                raise ConnectionError("mock servo bus closed the control socket")
            self._buf += chunk
        line, _, self._buf = self._buf.partition(b"\n")
        reply = json.loads(line)
        if not reply["ok"]:
            raise RuntimeError(reply["error"])
        return reply["result"]

    def close(self):
        self._sock.close()

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()
