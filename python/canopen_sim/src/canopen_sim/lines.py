"""The lines a child process writes, collected as they come, and waits for a line."""
import re
import threading
import time


class LineTimeout(AssertionError):
    """No line matched within the time given (an AssertionError, so that a test reads it as a
    failed expectation)."""


class Lines:
    """Every line of `stream` (a text pipe), kept in `lines` (newline stripped) by a daemon
    thread. `cond` guards `lines` and is notified on every line and at the end of the stream.

        out = Lines(proc.stdout, proc)
        mark = out.mark(); ...; out.wait(r"ready$", since=mark)
    """

    def __init__(self, stream, proc=None, name="output"):
        self.lines = []
        self.cond = threading.Condition()
        self.proc = proc
        self.name = name
        self.thread = threading.Thread(target=self._pump, args=(stream,), daemon=True)
        self.thread.start()

    def _pump(self, stream):
        for line in stream:
            with self.cond:
                self.lines.append(line.rstrip("\n"))
                self.cond.notify_all()
        with self.cond:
            self.cond.notify_all()

    def mark(self):
        """The position of the next line: a `since` for wait()."""
        with self.cond:
            return len(self.lines)

    def ended(self):
        """True once the stream is closed and every line of it is in `lines`."""
        return not self.thread.is_alive()

    def wait(self, pattern, since=0, timeout=5.0, count=1, context=None):
        """The re.Match objects of the first `count` lines at or after `since` that match
        `pattern`; raises LineTimeout when they do not come within `timeout` seconds or the
        stream ends first. `context`: a callable whose text the error message ends with."""
        rx = re.compile(pattern)
        deadline = time.monotonic() + timeout
        pos = since
        found = []
        with self.cond:
            while True:
                while pos < len(self.lines) and len(found) < count:
                    m = rx.search(self.lines[pos])
                    pos += 1
                    if m:
                        found.append(m)
                if len(found) >= count:
                    return found
                left = deadline - time.monotonic()
                if left <= 0 or self.ended():
                    why = "the stream ended" if self.ended() else f"{timeout} s passed"
                    if self.proc is not None and self.proc.poll() is not None:
                        why += f" (exit status {self.proc.returncode})"
                    more = context() if context is not None else ""
                    raise LineTimeout(f"no {count} x /{pattern}/ in the {self.name} before "
                                      f"{why}; got {len(found)}; its last lines: "
                                      f"{self.lines[since:][-10:]}{more}")
                self.cond.wait(min(left, 0.5))

    def join(self, timeout):
        """Waits up to `timeout` s for the end of the stream."""
        self.thread.join(timeout)
