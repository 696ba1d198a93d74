"""Ctrl-C (SIGINT) and SIGTERM for the render command.

Before rendering starts there is nothing to keep, so a signal stops the command at once
(`Interrupted`). Once rendering has started (`defer()`), the first signal is a request: the render
loop stops at the next pass boundary and the command writes what it has; a second one quits
immediately, writing nothing more (the files already written are whole: every write is atomic).

Python runs a signal handler only between bytecodes, and a Taichi kernel launch holds the
interpreter until it returns, so both take effect at the latest when the current pass ends (the
render loop keeps passes to about half a second).
"""
from __future__ import annotations

import os
import signal
import sys
import threading

STOP_SIGNALS = (signal.SIGINT, signal.SIGTERM)


def exit_code(signum: int) -> int:
    """The shell's convention: 128 + the signal's number (130 for SIGINT, 143 for SIGTERM)."""
    return 128 + int(signum)


class Interrupted(Exception):
    """A stop signal arrived before there was anything to save."""

    def __init__(self, signum: int):
        super().__init__(signum)
        self.signum = signum

    def __str__(self) -> str:
        return f"interrupted by {signal.Signals(self.signum).name}"


class StopRequests:
    """Installs handlers for STOP_SIGNALS while it is entered (`with StopRequests() as stop:`)."""

    def __init__(self, stream=None, quit_now=os._exit):
        self.signum: int | None = None
        self.deferring = False
        self._stream = stream
        self._quit_now = quit_now  # a parameter so that tests can watch it
        self._previous: dict[int, object] = {}

    def __enter__(self) -> "StopRequests":
        if threading.current_thread() is threading.main_thread():  # only there can handlers be set
            for signum in STOP_SIGNALS:
                self._previous[signum] = signal.signal(signum, self._handle)
        return self

    def __exit__(self, *exc) -> None:
        for signum, handler in self._previous.items():
            signal.signal(signum, handler)
        self._previous.clear()

    def defer(self) -> None:
        """From now on the first signal is a request to stop at a pass boundary."""
        self.deferring = True

    @property
    def requested(self) -> bool:
        return self.signum is not None

    @property
    def exit_code(self) -> int | None:
        return None if self.signum is None else exit_code(self.signum)

    def _handle(self, signum, _frame) -> None:
        if not self.deferring:
            raise Interrupted(signum)
        if self.signum is not None:
            self._say("interrupted again: quitting now")
            self._quit_now(exit_code(signum))
            return
        self.signum = signum
        self._say(f"{signal.Signals(signum).name}: stopping after this pass and writing the image so far "
                  "(Ctrl-C again to quit at once)")

    def _say(self, message: str) -> None:
        # os.write, not print: the handler may run in the middle of the progress bar's own write
        # to stderr, and a buffered stream refuses to be re-entered.
        stream = self._stream or sys.stderr
        text = f"\n{message}\n"
        try:
            os.write(stream.fileno(), text.encode())
        except (AttributeError, OSError, ValueError):  # no file descriptor (a captured stream)
            stream.write(text)
