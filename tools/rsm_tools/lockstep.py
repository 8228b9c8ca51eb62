"""Lockstep feeding of a reader process over pseudo-terminals (Linux).

A live reader stamps bytes with the time it reads them, so what it makes of
two links depends on when the machine runs it.  In lockstep the feeder waits
until the reader has taken every byte already written and is blocked waiting
for more (inside poll/select), holds it there, writes the next group of
records (everything recorded at one instant, on every link), and lets it go:
the reader then finds the whole group at once, in one wake-up, however busy
the machine is.  Its result is then a function of the bytes alone.

The reader is held with ptrace (PTRACE_SEIZE and PTRACE_INTERRUPT, Linux
3.4 and later), which tells where it stopped: in a wait that can block (poll,
select or epoll with a timeout that is not zero), or anywhere else, running
or in a non-blocking poll a read makes (then it is let go and asked again a
moment later).  ptrace on one's own child needs no privilege, so the feeder
starts the reader itself (rsm-replay --lockstep --run ...).  x86-64 Linux.
"""

import ctypes
import errno
import fcntl
import os
import platform
import struct
import termios
import time
from typing import Iterable, List, Optional, Sequence

PTRACE_PEEKDATA = 2
PTRACE_CONT = 7
PTRACE_GETREGS = 12
PTRACE_DETACH = 17
PTRACE_SEIZE = 0x4206
PTRACE_INTERRUPT = 0x4207
PTRACE_EVENT_STOP = 128
N_TTY_BUF = 4096  # a pty's input queue: more than this waits for the reader

# x86-64 user_regs_struct: the slots of the arguments and of the system call number.
REG_R10, REG_R8, REG_RDX, ORIG_RAX, N_REGS = 7, 9, 12, 15, 27
# The system calls a reader waits in, and where their timeout is: an int
# (0 = do not wait) or a pointer to a timespec/timeval (NULL = forever).
WAITS = {7: ("int", REG_RDX),         # poll
         271: ("time", REG_RDX),      # ppoll
         23: ("time", REG_R8),        # select
         270: ("time", REG_R8),       # pselect6
         232: ("int", REG_R10),       # epoll_wait
         281: ("int", REG_R10)}       # epoll_pwait


class LockstepError(Exception):
    pass


class ReaderGone(LockstepError):
    """The reader exited; ``status`` is its wait status."""

    def __init__(self, status: int) -> None:
        super().__init__(f"the reader ended (wait status {status})")
        self.status = status


def _libc():
    lib = ctypes.CDLL(None, use_errno=True)
    lib.ptrace.restype = ctypes.c_long
    lib.ptrace.argtypes = [ctypes.c_long, ctypes.c_long, ctypes.c_void_p, ctypes.c_void_p]
    return lib


def pending_input(fd: int) -> int:
    """Bytes written to a pty that its reader has not read yet (FIONREAD on the slave)."""
    return struct.unpack("i", fcntl.ioctl(fd, termios.FIONREAD, b"\0\0\0\0"))[0]


class Lockstep:
    """Holds the reader ``pid`` (a child of this process) between groups.

    ``slaves`` are file descriptors of the ptys' slave ends (opened by the
    feeder only to ask how much is unread).  Use :meth:`hold` before writing
    a group and :meth:`release` after it; :meth:`detach` at the end."""

    def __init__(self, pid: int, slaves: Iterable[int], poll_s: float = 0.0002, stall_s: Optional[float] = None,
                 names: Optional[Sequence[str]] = None) -> None:
        if platform.system() != "Linux" or platform.machine() != "x86_64":
            raise LockstepError(f"lockstep needs x86-64 Linux, not {platform.system()} {platform.machine()}")
        self.pid = pid
        self.slaves: List[int] = list(slaves)
        self.names: List[str] = list(names) if names is not None else [str(fd) for fd in self.slaves]
        self.poll_s = poll_s
        self.stall_s = stall_s
        self.libc = _libc()
        self.status: Optional[int] = None
        self.holds = 0
        self.retries = 0
        self._call(PTRACE_SEIZE, 0, "cannot trace the reader")

    def _call(self, req: int, data: int, what: str, addr: int = 0) -> None:
        if self.libc.ptrace(req, self.pid, ctypes.c_void_p(addr), ctypes.c_void_p(data)) != 0:
            e = ctypes.get_errno()
            if e == errno.ESRCH and self.status is None:
                self._reap()
            raise LockstepError(f"{what}: {os.strerror(e)}")

    def _reap(self) -> None:
        _, status = os.waitpid(self.pid, 0)
        self.status = status
        raise ReaderGone(status)

    def _peek(self, addr: int) -> int:
        ctypes.set_errno(0)
        v = self.libc.ptrace(PTRACE_PEEKDATA, self.pid, ctypes.c_void_p(addr), None)
        if v == -1 and ctypes.get_errno() != 0:
            raise LockstepError(f"cannot read the reader's memory: {os.strerror(ctypes.get_errno())}")
        return v

    def _waiting(self) -> bool:
        """True if the stopped reader is in a wait that can block."""
        regs = (ctypes.c_ulong * N_REGS)()
        self._call(PTRACE_GETREGS, ctypes.addressof(regs), "cannot read the reader's registers")
        wait = WAITS.get(ctypes.c_long(regs[ORIG_RAX]).value)
        if wait is None:
            return False
        kind, reg = wait
        if kind == "int":
            return ctypes.c_int(regs[reg] & 0xFFFFFFFF).value != 0
        ptr = regs[reg]
        return ptr == 0 or self._peek(ptr) != 0 or self._peek(ptr + 8) != 0

    def _stop(self) -> None:
        """Interrupts the reader and waits for that stop, passing on any signal it gets meanwhile."""
        self._call(PTRACE_INTERRUPT, 0, "cannot stop the reader")
        while True:
            _, status = os.waitpid(self.pid, 0)
            if os.WIFEXITED(status) or os.WIFSIGNALED(status):
                self.status = status
                raise ReaderGone(status)
            if status >> 16 == PTRACE_EVENT_STOP:
                return
            self._call(PTRACE_CONT, os.WSTOPSIG(status), "cannot resume the reader")

    def hold(self) -> None:
        """Returns once every written byte has been read and the reader is
        stopped while waiting for more."""
        last: Optional[List[int]] = None
        since = 0.0
        while True:
            pending = [pending_input(fd) for fd in self.slaves]
            if any(pending):
                # A reader that takes nothing from a link for stall_s while
                # bytes wait there never will: waiting for it would be for ever.
                now = time.monotonic()
                if pending != last:
                    last, since = pending, now
                elif self.stall_s is not None and now - since >= self.stall_s:
                    names = ", ".join(n for n, k in zip(self.names, pending) if k)
                    raise LockstepError(f"the reader read nothing from {names} for {self.stall_s:g} s "
                                        "while bytes waited there (--stall)")
                time.sleep(self.poll_s)
                continue
            self._stop()
            if self._waiting():
                self.holds += 1
                return
            self.retries += 1
            self._call(PTRACE_CONT, 0, "cannot resume the reader")
            time.sleep(self.poll_s)

    def release(self, written: Iterable[int]) -> None:
        """Lets the reader go once the bytes just written (per slave, in the
        order of ``slaves``) have all reached its input queue: a pty passes
        them on from a work queue, and a reader woken before that would take
        a group in two pieces."""
        want = [min(n, N_TTY_BUF - 1) for n in written]
        end = time.monotonic() + 5.0
        while any(pending_input(fd) < n for fd, n in zip(self.slaves, want)):
            if time.monotonic() > end:
                raise LockstepError("written bytes did not reach the reader's input queue in 5 s")
            time.sleep(self.poll_s / 4)
        self._call(PTRACE_CONT, 0, "cannot resume the reader")

    def detach(self) -> None:
        """Stops tracing (the reader runs on freely); safe after it ended."""
        if self.status is not None:
            return
        try:
            self._stop()
            self._call(PTRACE_DETACH, 0, "cannot detach from the reader")
        except ReaderGone:
            pass
