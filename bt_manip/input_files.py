"""Reading input files (trees, worlds, robot descriptors, URDFs, includes) within a size bound.

Every file bt-manip reads on a user's behalf goes through :func:`read_bounded`: it refuses what
is not a regular file (a directory, ``/dev/zero``, a FIFO) before reading anything, and reads at
most ``limit + 1`` bytes, so neither a device nor a huge file can exhaust memory. Problems
become an :class:`~bt_manip.errors.InputError` naming the file and the bound.
"""

from __future__ import annotations

import os
import stat
from pathlib import Path

from bt_manip.errors import InputError

MIB = 1024 * 1024


def size_text(n: int) -> str:
    """``10 MB`` for whole mebibytes, else the number of bytes."""
    return f"{n // MIB} MB" if n % MIB == 0 else f"{n} bytes"


def read_bounded(path: str | Path, limit: int, what: str = "file") -> bytes:
    """The bytes of ``path``, a regular file of at most ``limit`` bytes; InputError otherwise.

    ``what`` names the kind of file in the messages ("tree file", "URDF"...).
    """
    name = str(path)
    try:
        fd = os.open(name, os.O_RDONLY | getattr(os, "O_NONBLOCK", 0))
    except FileNotFoundError:
        raise InputError.single(name, None, f"{what} not found") from None
    except IsADirectoryError:
        raise _not_regular(name, what, "a directory") from None
    except OSError as exc:
        raise InputError.single(name, None, f"cannot read {what}: {exc.strerror}") from None
    try:
        mode = os.fstat(fd).st_mode
        if not stat.S_ISREG(mode):
            kind = (
                "a directory" if stat.S_ISDIR(mode)
                else "a device" if stat.S_ISCHR(mode) or stat.S_ISBLK(mode)
                else "a pipe" if stat.S_ISFIFO(mode)
                else "a socket" if stat.S_ISSOCK(mode)
                else "a special file"
            )
            raise _not_regular(name, what, kind)
        chunks: list[bytes] = []
        left = limit + 1
        while left > 0:
            chunk = os.read(fd, min(left, MIB))
            if not chunk:
                break
            chunks.append(chunk)
            left -= len(chunk)
    except OSError as exc:
        raise InputError.single(name, None, f"cannot read {what}: {exc.strerror}") from None
    finally:
        os.close(fd)
    data = b"".join(chunks)
    if len(data) > limit:
        raise InputError.single(
            name, None, f"{what} is larger than the limit of {size_text(limit)}"
        )
    return data


def _not_regular(name: str, what: str, kind: str) -> InputError:
    return InputError.single(name, None, f"{what} is {kind}, not a regular file")


def line_of_text(data: bytes, text: str) -> int | None:
    """1-based line of the first quoted occurrence of ``text`` in ``data`` (None if absent)."""
    needle = text.encode("utf-8", errors="replace")
    for quote in (b'"', b"'"):
        at = data.find(quote + needle + quote)
        if at >= 0:
            return data.count(b"\n", 0, at) + 1
    return None
