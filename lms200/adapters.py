"""Put a :class:`~lms200.virtual.VirtualLMS200` on a pseudo-terminal or a TCP port.

Each adapter runs one thread that moves bytes between the device and its port and paces the
device's output by the device's baud. Both are context managers; ``close()`` stops the thread.

- :class:`PtyAdapter`: ``adapter.path`` (``/dev/pts/N``) opens like a serial port. The host's baud
  (its termios setting) is compared with the device's: when they differ, both directions are
  garbled as a real UART would garble them, so baud probing and baud changes are exercised.
- :class:`TcpServer`: ``adapter.url`` (``socket://127.0.0.1:PORT``), one client at a time; a raw TCP
  stream carries no baud, so only the pacing follows the device's baud. With ``rfc2217=True``
  (``rfc2217://127.0.0.1:PORT``) the host sets the baud over RFC 2217 and mismatches garble. The device keeps its state
  (baud, mode) across connections, like a unit that stays powered.

Bytes the host does not read are dropped once its receive buffer is full (a UART overrun), so a
device in continuous mode never blocks the adapter. That buffer lasts as long in the device's time
as in real time: the kernel's buffer (20 KiB on a pty here) plus, for a device at ``time_scale`` < 1,
:data:`HOST_BUFFER_BYTES` / ``time_scale`` - :data:`HOST_BUFFER_BYTES` bytes the adapter holds
for the host (none at time_scale 1 or above; at most :data:`MAX_HELD_BYTES`, 1 MiB, so memory stays
bounded at any time_scale). Held bytes are dropped when the host's baud changes (a new host, or the
driver probing bauds), also when it changes between the adapter reading it and writing (the
host's baud is read again around each write to the pty): they were garbled for the baud of the host that left them, and a new host
at 9600 baud read 424 kB of a stream left running at 500000 as valid frames at 9600 and never
probed on (a review: reconnecting to a scaled device left streaming failed). At time_scale 0.01 the line carries 100 times its baud (192 kB/s
at 19200 baud): the kernel's buffer alone was full after a 0.1 s pause of the host (a loaded
machine), and the bytes behind it were lost; a real host at 19200 baud fills 4 KiB in 2.1 s.
"""

from __future__ import annotations

import os
import select
import socket
import termios
import threading
import time
import tty
from typing import Callable

import numpy as np

from .errors import InputError
from .finite import check_integer
from .finite import shown as shown_value
from .virtual import VirtualLMS200, garble

_TICK_S = 0.002  # longest sleep between pacing steps
_IDLE_S = 0.05  # sleep while the device has nothing to send
HOST_BUFFER_BYTES = 4096  # a serial port's receive buffer (the kernel's tty buffer: 4 KiB at least)
_WRITE_MAX = 65536  # bytes offered to the port per write
MAX_HELD_BYTES = 1 << 20  # bytes held for the host at most, whatever the time_scale (memory bound)
_SPEEDS = {getattr(termios, f"B{b}"): b for b in (9600, 19200, 38400, 57600, 115200, 230400, 500000) if hasattr(termios, f"B{b}")}


class _Adapter:
    def __init__(self, device: VirtualLMS200, clock: Callable[[], float] = time.monotonic) -> None:
        if not isinstance(device, VirtualLMS200):  # None ran a thread that died at once, an AttributeError at close()
            raise InputError(f"device: must be an lms200.virtual.VirtualLMS200, got {type(device).__name__}")
        if not callable(clock):
            raise InputError(f"clock: must be a function giving seconds, got {shown_value(clock)}")
        self.device = device
        self.clock = clock
        self.overrun_bytes = 0
        self._pending = bytearray()  # bytes due that the port did not take yet (see the module doc)
        self._pending_baud: int | None = None  # the host's baud they were garbled for
        self._stop = threading.Event()
        self._lock = threading.Lock()
        #: what stopped the adapter's thread (the device's source raised, or gave an item that is no
        #: Scan), or None; ``close()`` raises it. It was a traceback from the thread on stderr, and the
        #: host saw only its driver's timeout (a library walkthrough fed ``read_log``'s records).
        self.error: BaseException | None = None
        self._thread = threading.Thread(target=self._guarded, name=type(self).__name__, daemon=True)

    def start(self) -> None:
        self._thread.start()

    def _timeout(self) -> float:
        now = self.clock()
        with self._lock:
            wake = self.device.next_wakeup(now)
        if self._pending:
            return _TICK_S
        if wake is None:
            return _IDLE_S
        return min(_TICK_S, max(0.0, wake - now))

    def _exchange(self, data: bytes | None, host_baud: int | None, write: Callable[[bytes], int] | None) -> None:
        """Feed host bytes to the device and write its due bytes (dropping what does not fit)."""
        with self._lock:
            dev = self.device
            if data:
                dev.receive(garble(data, host_baud or dev.baud, dev.baud), self.clock())
            if host_baud != self._pending_baud:  # a host at another baud (a new one, or the driver's
                self._pending.clear()  # probe): what the last took at its baud is not this one's input
                self._pending_baud = host_baud
            for piece, baud in dev.transmit(self.clock()):
                if write is not None:
                    self._pending += garble(piece, baud, host_baud or baud)
            if write is None:
                self._pending.clear()  # no host: the bytes go nowhere
            elif self._pending:
                self._deliver(write)

    def _deliver(self, write: Callable[[bytes], int]) -> None:
        """Write the bytes due; keep what the port does not take, up to the spare buffer, and drop
        the newest beyond it (an overrun)."""
        pending = self._pending
        try:
            sent = write(bytes(pending[:_WRITE_MAX]))
        except (BlockingIOError, InterruptedError):
            sent = 0
        except OSError:  # the host went away mid-write: the bytes are lost
            sent = len(pending)
        del pending[:sent]
        spare = min(MAX_HELD_BYTES, HOST_BUFFER_BYTES * (1.0 / self.device.time_scale - 1.0))
        excess = len(pending) - max(0, int(spare))
        if excess > 0:
            del pending[len(pending) - excess :]
            self.overrun_bytes += excess

    def _run(self) -> None:  # pragma: no cover - overridden
        raise NotImplementedError

    def _guarded(self) -> None:
        try:
            self._run()
        except BaseException as exc:  # kept for close(), which raises it in the caller's thread
            self.error = exc

    def _release(self) -> None:
        """Release the port (after the thread has stopped)."""

    def close(self) -> None:
        """Stop the thread and release the port; then raise what stopped the thread, if anything
        did (``error``: the device's source raised, or gave an item that is no Scan), once."""
        self._stop.set()
        if self._thread.is_alive():
            self._thread.join(timeout=2.0)
        self._release()
        error, self.error = self.error, None
        if error is not None:
            raise error

    def __enter__(self) -> "_Adapter":
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


class PtyAdapter(_Adapter):
    """The device on a new pseudo-terminal; open ``adapter.path`` with any serial client."""

    def __init__(self, device: VirtualLMS200, clock: Callable[[], float] = time.monotonic) -> None:
        super().__init__(device, clock)
        self._master, self._slave = os.openpty()
        tty.setraw(self._slave)
        os.set_blocking(self._master, False)
        self.path = os.ttyname(self._slave)
        self.start()

    def host_baud(self) -> int | None:
        """The baud the host has set on its end of the terminal (None if not a known speed)."""
        try:
            return _SPEEDS.get(termios.tcgetattr(self._slave)[5])
        except termios.error:
            return None

    def _write(self, data: bytes) -> int:
        """Write bytes garbled for the host's baud as the exchange read it; the host may set
        another baud (and flush its input) meanwhile, from its own process or thread, and then
        must not read them: a host probing at 9600 read frames sent clean at 38400, and took
        9600 for the device's baud (a loaded machine). So the baud is read again just before
        the write (changed: the bytes are dropped, and the next exchange garbles for the new
        baud) and just after it (changed during the write: the host's input is flushed)."""
        if self.host_baud() != self._pending_baud:
            return len(data)  # dropped: garbled for a baud the host has left
        sent = os.write(self._master, data)
        if self.host_baud() != self._pending_baud:
            try:
                termios.tcflush(self._slave, termios.TCIFLUSH)
            except termios.error:
                pass
        return sent

    def _run(self) -> None:
        while not self._stop.is_set():
            ready, _, _ = select.select([self._master], [], [], self._timeout())
            data = None
            if ready:
                try:
                    data = os.read(self._master, 4096)
                except (BlockingIOError, InterruptedError):
                    data = None
                except OSError:  # EIO: no process holds the terminal open
                    data = None
            self._exchange(data, self.host_baud(), self._write)

    def _release(self) -> None:
        for fd in (self._master, self._slave):
            try:
                os.close(fd)
            except OSError:
                pass


class _LineSettings:
    """The serial-port attributes pyserial's RFC 2217 server side reads and sets."""

    def __init__(self) -> None:
        self.baudrate = 9600
        self.bytesize, self.parity, self.stopbits = 8, "N", 1
        self.xonxoff = self.rtscts = self.break_condition = False
        self.dtr = self.rts = True
        self.cts = self.dsr = self.ri = self.cd = False

    def reset_input_buffer(self) -> None:
        pass

    def reset_output_buffer(self) -> None:
        pass


class _SocketWriter:
    def __init__(self, sock: socket.socket) -> None:
        self.sock = sock

    def write(self, data: bytes) -> None:
        try:
            self.sock.send(data)
        except OSError:
            pass


class TcpServer(_Adapter):
    """The device behind a TCP port: ``adapter.url`` = ``socket://HOST:PORT`` for pyserial. An
    IPv6 ``host`` (``::1``, or ``[::1]`` as in a URL) listens on IPv6, its URL bracketed
    (``socket://[::1]:PORT``): it was bound as IPv4, "Address family for hostname not supported".

    With ``rfc2217=True`` the port speaks RFC 2217 (``rfc2217://HOST:PORT``): the host sets the
    line's baud over the network, and as on the pseudo-terminal a baud that differs from the
    device's garbles both directions.
    """

    def __init__(self, device: VirtualLMS200, host: str = "127.0.0.1", port: int = 0,
                 clock: Callable[[], float] = time.monotonic, rfc2217: bool = False) -> None:
        if not isinstance(host, str) or not host:  # None was an AttributeError ('startswith')
            raise InputError(f"host: must be an address or a host name (127.0.0.1, ::1, localhost), got {shown_value(host)}")
        # a bool port (True bound port 1), 99999 (OverflowError), 1.5 or text (TypeError)
        port = check_integer(port, "port", 0, 65535, "(0: a free one)", strict=True)
        super().__init__(device, clock)
        bare = host[1:-1] if host.startswith("[") and host.endswith("]") else host
        self._listener = socket.create_server((bare, port), family=socket.AF_INET6 if ":" in bare else socket.AF_INET)
        self._listener.setblocking(False)
        self.host, self.port = self._listener.getsockname()[:2]
        self.rfc2217 = rfc2217
        shown = f"[{self.host}]" if ":" in self.host else self.host
        self.url = f"{'rfc2217' if rfc2217 else 'socket'}://{shown}:{self.port}"
        self.connections = 0
        self._manager = None
        self._line = _LineSettings()
        self.start()

    def _accepted(self, client: socket.socket) -> None:
        if self.rfc2217:
            from serial.rfc2217 import PortManager

            self._line = _LineSettings()
            self._manager = PortManager(self._line, _SocketWriter(client))

    def _from_host(self, data: bytes) -> bytes:
        if self._manager is None or not data:
            return data
        return b"".join(self._manager.filter(data))

    def _send(self, client: socket.socket) -> Callable[[bytes], int]:
        if self._manager is None:
            return client.send
        manager = self._manager

        def send(data: bytes) -> int:
            escaped = b"".join(manager.escape(data))
            sent = client.send(escaped)
            if sent == len(escaped):
                return len(data)
            # the data bytes whose escaped form went out whole (0xFF is sent as FF FF)
            return int(np.searchsorted(np.cumsum(1 + (np.frombuffer(data, np.uint8) == 0xFF)), sent, side="right"))

        return send

    def _run(self) -> None:
        client: socket.socket | None = None
        while not self._stop.is_set():
            watch = [client] if client is not None else [self._listener]
            ready, _, _ = select.select(watch, [], [], self._timeout())
            data = None
            if ready and client is None:
                try:
                    client, _ = self._listener.accept()
                    client.setblocking(False)
                    client.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
                    self.connections += 1
                    self._accepted(client)
                except (BlockingIOError, InterruptedError):
                    client = None
            elif ready and client is not None:
                try:
                    data = client.recv(4096)
                except (BlockingIOError, InterruptedError):
                    data = None
                except OSError:
                    data = b""
                if data == b"":  # the host hung up: wait for the next one
                    client.close()
                    client, data, self._manager = None, None, None
                elif data is not None:
                    data = self._from_host(data)
            host_baud = self._line.baudrate if self._manager is not None else None
            self._exchange(data, host_baud, self._send(client) if client is not None else None)
        if client is not None:
            client.close()

    def _release(self) -> None:
        self._listener.close()
