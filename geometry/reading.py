"""One bounded reader for every file the tool reads: design files, sweep specs, material
files, materials sidecars, bench data and CAD files.

``open_regular`` opens a path without blocking (a FIFO with no writer would hang a plain
``open``) and refuses anything but a regular file by name (a FIFO, a character or block
device such as /dev/zero, a socket, a directory) and anything larger than the cap before
reading a byte. ``read_bytes`` reads at most the cap; ``read_text`` decodes UTF-8 (a file
saved as UTF-16 or of random bytes is one line); ``read_toml``/``read_json`` parse and bound
the nesting depth (a parse too deep for the parser, RecursionError, is the same line). Every
refusal is a ParameterError "WHAT PATH: why" on one line.

It lives in ``geometry`` (the bottom layer) so that the material loaders of ``geometry`` and
``magnetics`` use it too; ``mrclutch.inputs`` re-exports it for the application.
"""

from __future__ import annotations

import errno
import json
import os
import stat
from collections.abc import Mapping
from pathlib import Path
from typing import Any

from geometry.validation import ParameterError

#: bytes: the largest text input read (the paper's design file is 1.2 kB, a material 2 kB).
MAX_INPUT_BYTES = 1 << 20
#: bytes: the largest CAD file (STEP/STL) weighed: a clutch's STEP is ~1 MB, a fine STL
#: of one part ~10 MB; 256 MiB keeps the mesh in memory well under 1 GiB.
MAX_CAD_BYTES = 256 << 20
#: tables and arrays inside one another: a design file has 2 levels, a spec 3, a material 3.
MAX_DEPTH = 8

_KINDS = ((stat.S_ISFIFO, "a FIFO (named pipe)"), (stat.S_ISCHR, "a character device"),
          (stat.S_ISBLK, "a block device"), (stat.S_ISSOCK, "a socket"),
          (stat.S_ISDIR, "a directory"))  # fmt: skip


def _open(p: Path, what: str, cap: int) -> int:
    """A read-only descriptor of the regular file ``p`` of at most ``cap`` bytes."""
    try:
        fd = os.open(p, os.O_RDONLY | os.O_NONBLOCK | getattr(os, "O_NOCTTY", 0))
    except FileNotFoundError:
        raise ParameterError(f"{what} {p}: not found") from None
    except OSError as exc:
        why = "is a directory" if exc.errno == errno.EISDIR else (exc.strerror or str(exc))
        raise ParameterError(f"{what} {p}: {why}") from None
    try:
        st = os.fstat(fd)
        if not stat.S_ISREG(st.st_mode):
            kind = next((k for test, k in _KINDS if test(st.st_mode)), "not a regular file")
            raise ParameterError(f"{what} {p}: is {kind}, not a regular file")
        if st.st_size > cap:
            raise ParameterError(f"{what} {p}: {st.st_size} bytes; {what}s are read up to "
                                 f"{cap} bytes")  # fmt: skip
    except BaseException:
        os.close(fd)
        raise
    return fd


def check_regular(path: str | Path, what: str, cap: int = MAX_CAD_BYTES) -> Path:
    """``path`` if it is a regular file of at most ``cap`` bytes (for readers that open the
    file themselves: trimesh, OpenCascade), else the one-line ParameterError."""
    p = Path(path)
    os.close(_open(p, what, cap))
    return p


def read_bytes(path: str | Path, what: str, cap: int = MAX_INPUT_BYTES) -> bytes:
    """The bytes of the regular file ``path`` (at most ``cap``), or a one-line
    ParameterError "``what`` PATH: why"."""
    p = Path(path)
    fd = _open(p, what, cap)
    try:
        with os.fdopen(fd, "rb", closefd=True) as f:
            fd = -1
            raw = f.read(cap + 1)
    except OSError as exc:
        raise ParameterError(f"{what} {p}: cannot read ({exc.strerror or exc})") from None
    finally:
        if fd >= 0:
            os.close(fd)
    if len(raw) > cap:  # it grew since fstat
        raise ParameterError(f"{what} {p}: more than {cap} bytes")
    return raw


def read_text(path: str | Path, what: str, cap: int = MAX_INPUT_BYTES) -> str:
    """The UTF-8 text of the regular file ``path`` (``read_bytes``); a file that is not
    UTF-8 (random bytes, UTF-16) is one line naming the file."""
    return decode_text(read_bytes(path, what, cap), path, what)


def decode_text(raw: bytes, path: str | Path, what: str) -> str:
    """``raw`` (the bytes of ``path``) as UTF-8 text, or ``read_text``'s one line."""
    try:
        return raw.decode("utf-8")
    except UnicodeDecodeError as exc:
        hint = (
            "; saved as UTF-16? save it as UTF-8" if raw[:2] in (b"\xff\xfe", b"\xfe\xff") else ""
        )
        raise ParameterError(f"{what} {path}: not UTF-8 text ({exc.reason} at byte "
                             f"{exc.start}{hint})") from None  # fmt: skip


def read_toml(path: str | Path, what: str) -> dict[str, Any]:
    """``read_text`` parsed as TOML, its nesting checked (``check_depth``)."""
    return parse_toml(read_text(path, what), path, what)


def parse_toml(text: str, path: str | Path, what: str) -> dict[str, Any]:
    """``text`` (of ``path``) parsed as TOML, its nesting checked, or ``read_toml``'s line."""
    # imported here: tomllib (pure Python, its regexes compiled at import) is ~18M
    # instructions, 4 % of a preset's analytic inertia, and a command on a preset reads the
    # materials from their cache (geometry.materials) without parsing a TOML file
    import tomllib

    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise ParameterError(f"{what} {path}: not valid TOML ({exc})") from None
    except RecursionError:
        raise ParameterError(f"{what} {path}: nested too deeply to parse (tables and arrays "
                             f"go at most {MAX_DEPTH} deep)") from None  # fmt: skip
    check_depth(data, f"{what} {path}")
    return data


def read_json(path: str | Path, what: str) -> Any:
    """``read_text`` parsed as JSON (NaN and ±Infinity refused), its nesting checked."""
    text = read_text(path, what)

    def no_constant(name: str) -> Any:
        raise ValueError(f"{name} is not a number JSON allows")

    try:
        data = json.loads(text, parse_constant=no_constant)
    except (ValueError, RecursionError) as exc:
        why = "nested too deeply to parse" if isinstance(exc, RecursionError) else str(exc)
        raise ParameterError(f"{what} {path}: not valid JSON ({why})") from None
    check_depth(data, f"{what} {path}")
    return data


def check_depth(value: Any, where: str, key: str = "", depth: int = 0) -> None:
    """Refuse tables/arrays nested more than MAX_DEPTH deep, naming the first such key."""
    if depth > MAX_DEPTH:
        raise ParameterError(f"{where}: {key or 'the file'}: nested more than {MAX_DEPTH} "
                             "levels deep")  # fmt: skip
    if isinstance(value, Mapping):
        for k, v in value.items():
            check_depth(v, where, f"{key}.{k}" if key else str(k), depth + 1)
    elif isinstance(value, list):
        for i, v in enumerate(value):
            check_depth(v, where, f"{key}[{i}]", depth + 1)
