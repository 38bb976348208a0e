"""Messages between the grader and the process that runs a student's code, over two pipes.

A message is a list of byte strings ("parts"): a 4-byte count, then each part as an 8-byte
length and its bytes. The grader's side (``Channel``) never blocks: every read and write
waits at most until a deadline, a message larger than a limit is refused, and the bytes
the student's process prints (its stdout and stderr, a third pipe) are read meanwhile so
that it never stalls on a full pipe. Whatever arrives is only bytes here; what they may
mean is decided by ``ptlab.course.sandbox.plain_data``. The child's side (``read_message``,
``write_message``) simply blocks: it has nothing to protect.
"""

from __future__ import annotations

import contextlib
import fcntl
import os
import select
import struct
import time
from collections.abc import Callable

import numpy as np

from ptlab.course.sandbox.shown import shown

COUNT = struct.Struct("<I")
LENGTH = struct.Struct("<Q")
#: Parts in one message, at most (a reply's arrays, one part each).
MAX_PARTS = 100_000
#: Bytes of a student's printed output passed on per process, at most; the rest is read and dropped.
MAX_OUTPUT = 64 * 1024
#: Pipe buffers of 1 MiB instead of Linux's 64 KiB: large arrays cross in fewer wake-ups.
PIPE_SIZE = 1 << 20
READ_AHEAD = 1 << 16
#: A part as read: a ``bytearray``, or for a large one NumPy's bytes, not zeroed (``_buffer``).
Part = bytearray | np.ndarray


class ChannelClosedError(Exception):
    """The other side closed its end (the student's process ended)."""


class ChannelTimeoutError(Exception):
    """The deadline passed before the message was complete."""


class ChannelError(Exception):
    """The bytes do not form a message within the limits."""


def enlarge(fd: int) -> None:
    """Give the pipe ``fd`` a 1 MiB buffer where the system allows it."""
    with contextlib.suppress(AttributeError, OSError):
        fcntl.fcntl(fd, fcntl.F_SETPIPE_SZ, PIPE_SIZE)


class Channel:
    """The grader's end: ``send`` and ``receive`` messages, each by a deadline.

    Args:
        send_fd: the pipe the child reads requests from.
        receive_fd: the pipe the child writes replies to.
        output_fd: the pipe the child's stdout and stderr go to (or None).
        on_output: called with each line the child printed, up to ``MAX_OUTPUT`` bytes,
            shown (one line, its control characters escaped).
    """

    def __init__(
        self,
        send_fd: int,
        receive_fd: int,
        output_fd: int | None = None,
        on_output: Callable[[str], None] | None = None,
    ):
        for fd in (send_fd, receive_fd, output_fd):
            if fd is not None:
                os.set_blocking(fd, False)
        # (None once ``close`` closed them.)
        self.send_fd: int | None = send_fd
        self.receive_fd: int | None = receive_fd
        self.output_fd = output_fd
        self.on_output = on_output
        self._output = bytearray()
        self._output_passed = 0
        self._pending = bytearray()  # bytes read ahead, past the part being read

    # -- sending ----------------------------------------------------------------------

    def send(self, parts: list, deadline: float) -> None:
        chunks = _chunks(parts)
        while chunks:
            try:
                written = os.writev(_open(self.send_fd), chunks[:512])
            except BlockingIOError:  # the pipe is full: wait until the child reads
                self._wait(_open(self.send_fd), select.POLLOUT, deadline)
                continue
            except (BrokenPipeError, ConnectionResetError):
                raise ChannelClosedError from None
            _advance(chunks, written)

    # -- receiving --------------------------------------------------------------------

    def receive(self, deadline: float, limit: int) -> list[Part]:
        """The next message; at most ``limit`` bytes of parts in all."""
        (count,) = COUNT.unpack(_view(self._read(COUNT.size, deadline)))
        if count > MAX_PARTS:
            raise ChannelError(f"a message of {count} parts")
        lengths = struct.unpack(f"<{count}Q", _view(self._read(LENGTH.size * count, deadline)))
        if sum(lengths) > limit:
            raise ChannelError(f"a message of {sum(lengths):,} bytes (the limit is {limit:,})")
        return [self._read(length, deadline) for length in lengths]

    def _read(self, size: int, deadline: float) -> Part:
        """``size`` bytes: small reads go through a read-ahead buffer (one system call for
        a whole small message), large ones straight into their own buffer."""
        if len(self._pending) >= size:
            return _take(self._pending, size)
        buffer, view, filled = _seeded_buffer(self._pending, size)
        while filled < size:
            receive_fd = _open(self.receive_fd)
            self._wait(receive_fd, select.POLLIN, deadline)
            try:
                if size - filled < READ_AHEAD:
                    data = os.read(receive_fd, READ_AHEAD)
                    got = min(len(data), size - filled)
                    view[filled : filled + got] = data[:got]
                    self._pending += data[got:]
                else:
                    got = os.readv(receive_fd, [view[filled:]])
            except BlockingIOError:
                continue
            if got == 0:
                raise ChannelClosedError
            filled += got
        return buffer

    # -- waiting, and passing on what the child prints ----------------------------------

    def _wait(self, fd: int, event: int, deadline: float) -> None:
        """Return when ``fd`` is ready for ``event``, reading the child's output meanwhile."""
        poller = select.poll()
        poller.register(fd, event)
        if self.output_fd is not None:
            poller.register(self.output_fd, select.POLLIN)
        while True:
            left = deadline - time.monotonic()
            if left <= 0:
                raise ChannelTimeoutError
            ready = poller.poll(min(left, 3600) * 1000)
            for ready_fd, flags in ready:
                if ready_fd == self.output_fd:
                    if not self._drain_output(ready_fd):
                        poller.unregister(self.output_fd)
                        os.close(self.output_fd)
                        self.output_fd = None
                elif flags & (event | select.POLLHUP | select.POLLERR):
                    return

    def _drain_output(self, output_fd: int) -> bool:
        """Read what the child printed (the pipe ``output_fd``); False once its end is closed."""
        try:
            data = os.read(output_fd, READ_AHEAD)
        except BlockingIOError:
            return True
        self._take_output(data)
        return bool(data)

    def _take_output(self, data: bytes) -> None:
        room = MAX_OUTPUT - self._output_passed
        if room <= 0:
            return
        self._output += data[:room]
        self._output_passed += min(len(data), room)
        *lines, rest = self._output.split(b"\n")
        self._output = bytearray(rest)
        for line in lines:
            self._pass(line)
        if len(data) >= room:
            self._pass(self._output + b" [... the rest of the output is dropped]")
            self._output = bytearray()

    def flush_output(self) -> None:
        """Pass on what is left in the output pipe, and a last line without a newline."""
        if self.output_fd is not None:
            try:
                while data := os.read(self.output_fd, READ_AHEAD):
                    self._take_output(data)
            except OSError:
                pass
        if self._output:
            self._pass(self._output)
            self._output = bytearray()

    def _pass(self, line: bytes | bytearray) -> None:
        """Pass on one line, shown (``ptlab.course.sandbox.shown``: an ANSI escape or a carriage
        return in it cannot rewrite the grader's lines on a terminal). An ``on_output`` that
        raises (its reader went away) gets nothing more: the grading goes on, and ends."""
        if self.on_output is None:
            return
        try:
            self.on_output(shown(line.decode("utf-8", "replace").removesuffix("\r")))
        except Exception:
            self.on_output = None

    def close(self) -> None:
        self.flush_output()
        for fd in (self.send_fd, self.receive_fd, self.output_fd):
            if fd is not None:
                with contextlib.suppress(OSError):
                    os.close(fd)
        self.send_fd = self.receive_fd = self.output_fd = None


# -- the child's side -----------------------------------------------------------------


class Reader:
    """The child's end of the request pipe: whole messages, read ahead in large chunks
    (one system call for a small message: every call's round trip counts)."""

    def __init__(self, fd: int):
        self.fd = fd
        self._pending = bytearray()

    def _read(self, size: int) -> Part:
        while len(self._pending) < size:
            want = size - len(self._pending)
            if want >= READ_AHEAD:
                buffer, view, filled = _seeded_buffer(self._pending, size)
                while filled < size:
                    got = os.readv(self.fd, [view[filled:]])
                    if got == 0:
                        raise ChannelClosedError
                    filled += got
                return buffer
            data = os.read(self.fd, READ_AHEAD)
            if not data:
                raise ChannelClosedError
            self._pending += data
        return _take(self._pending, size)

    def read_message(self) -> list[Part]:
        """The next message from the grader (blocking)."""
        (count,) = COUNT.unpack(_view(self._read(COUNT.size)))
        lengths = struct.unpack(f"<{count}Q", _view(self._read(LENGTH.size * count)))
        return [self._read(length) for length in lengths]


def write_message(fd: int, parts: list) -> None:
    """Send a message to the grader (blocking), with as few system calls as it takes."""
    chunks = _chunks(parts)
    while chunks:
        written = os.writev(fd, chunks[:512])
        _advance(chunks, written)


def _buffer(size: int) -> tuple[Part, memoryview]:
    """A buffer to read ``size`` bytes into, and a view of it: a large one is not zeroed
    first (NumPy's ``empty``; a ``bytearray`` of 24 MB costs milliseconds of zeroing, every
    call)."""
    if size < READ_AHEAD:
        buffer = bytearray(size)
        return buffer, memoryview(buffer)
    array = np.empty(size, np.uint8)
    return array, array.data  # (its memoryview: see _view)


def _seeded_buffer(pending: bytearray, size: int) -> tuple[Part, memoryview, int]:
    """A buffer for ``size`` bytes that begins with the bytes already read ahead,
    ``pending`` (which it empties): the buffer, a view to read the rest into, and how many
    bytes it holds already."""
    buffer, view = _buffer(size)
    filled = len(pending)
    view[:filled] = pending
    pending.clear()
    return buffer, view, filled


def _view(part: Part) -> bytearray | memoryview:
    """``part`` as a buffer for ``struct`` (an array's ``.data``, its memoryview: NumPy's stubs
    declare an array's buffer protocol for Python 3.12 on only)."""
    return part.data if isinstance(part, np.ndarray) else part


def _open(fd: int | None) -> int:
    """``fd``, one of a channel's pipes, unless ``Channel.close`` closed it (then an error, as
    Python's own files raise)."""
    if fd is None:
        raise ValueError("I/O operation on a closed channel")
    return fd


def _take(pending: bytearray, size: int) -> bytearray:
    """The first ``size`` bytes of ``pending``, removed from it."""
    taken = pending[:size]
    del pending[:size]
    return taken


def _chunks(parts: list) -> list[memoryview]:
    """A message as the byte views to write: the header, then each part (a part may be a
    tuple of buffers, sent one after the other, to save joining them)."""
    lengths, views = [], []
    for part in parts:
        pieces = (
            [memoryview(b).cast("B") for b in part]
            if isinstance(part, tuple)
            else [memoryview(part).cast("B")]
        )
        lengths.append(sum(map(len, pieces)))
        views.extend(pieces)
    header = COUNT.pack(len(parts)) + struct.pack(f"<{len(lengths)}Q", *lengths)
    return [memoryview(header)] + [view for view in views if len(view)]


def _advance(chunks: list[memoryview], written: int) -> None:
    """Drop the first ``written`` bytes of ``chunks`` (after a partial write)."""
    while written and chunks:
        if written >= len(chunks[0]):
            written -= len(chunks[0])
            chunks.pop(0)
        else:
            chunks[0] = chunks[0][written:]
            written = 0
