"""Reading the user's input files (design files, sweep specs): bounded and regular only.

A design or spec file is a few kB of TOML. ``read_toml`` opens it without blocking (a
FIFO with no writer would hang a plain ``open``), refuses anything but a regular file (a
FIFO, a device such as /dev/zero, a socket) and anything larger than ``MAX_INPUT_BYTES``
before reading it, and reads at most that many bytes; a parse too deep for the parser
(RecursionError) or a structure nested deeper than ``MAX_DEPTH`` is one error naming the
key. Every refusal is a ParameterError naming the file.
"""

from __future__ import annotations

import errno
import math
import os
import stat
import tomllib
from collections.abc import Mapping
from pathlib import Path
from typing import Any

from geometry.validation import ParameterError

#: bytes: the largest input file read (the paper's design file is 1.2 kB).
MAX_INPUT_BYTES = 1 << 20
#: tables and arrays inside one another: a design file has 2 levels, a spec 3.
MAX_DEPTH = 8

_KINDS = ((stat.S_ISFIFO, "a FIFO (named pipe)"), (stat.S_ISCHR, "a character device"),
          (stat.S_ISBLK, "a block device"), (stat.S_ISSOCK, "a socket"),
          (stat.S_ISDIR, "a directory"))  # fmt: skip


def read_text(path: str | Path, what: str) -> str:
    """The UTF-8 text of the regular file ``path`` (at most MAX_INPUT_BYTES), or a one-line
    ParameterError "``what`` PATH: why"."""
    p = Path(path)
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
        if st.st_size > MAX_INPUT_BYTES:
            raise ParameterError(f"{what} {p}: {st.st_size} bytes; input files are read up "
                                 f"to {MAX_INPUT_BYTES} bytes")  # fmt: skip
        with os.fdopen(fd, "rb", closefd=True) as f:
            fd = -1
            raw = f.read(MAX_INPUT_BYTES + 1)
    except OSError as exc:
        raise ParameterError(f"{what} {p}: cannot read ({exc.strerror or exc})") from None
    finally:
        if fd >= 0:
            os.close(fd)
    if len(raw) > MAX_INPUT_BYTES:  # it grew since fstat
        raise ParameterError(f"{what} {p}: more than {MAX_INPUT_BYTES} bytes")
    try:
        return raw.decode("utf-8")
    except UnicodeDecodeError as exc:
        raise ParameterError(f"{what} {p}: not UTF-8 text ({exc.reason})") from None


def read_toml(path: str | Path, what: str) -> dict[str, Any]:
    """``read_text`` parsed as TOML, its nesting checked (``check_depth``)."""
    text = read_text(path, what)
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise ParameterError(f"{what} {path}: not valid TOML ({exc})") from None
    except RecursionError:
        raise ParameterError(f"{what} {path}: nested too deeply to parse (tables and arrays "
                             f"go at most {MAX_DEPTH} deep)") from None  # fmt: skip
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


#: TOML basic-string escapes; other control characters as \uXXXX (TOML 1.0 §String).
_ESCAPES = {"\\": "\\\\", '"': '\\"', "\b": "\\b", "\t": "\\t", "\n": "\\n",
            "\f": "\\f", "\r": "\\r"}  # fmt: skip


def toml_value(v: Any) -> str:
    """``v`` (a string, bool, int or float) as a TOML value: a basic string with its
    control characters escaped, ``inf`` as TOML's inf; what ``design_to_toml`` and
    ``uncertainty.measured_to_toml`` write."""
    if isinstance(v, str):
        out = []
        for ch in v:
            code = ord(ch)
            if ch in _ESCAPES:
                out.append(_ESCAPES[ch])
            elif code < 0x20 or code == 0x7F:
                out.append(f"\\u{code:04X}")
            elif 0xD800 <= code <= 0xDFFF:  # a lone surrogate (an undecodable file name)
                out.append("\\uFFFD")
            else:
                out.append(ch)
        return '"' + "".join(out) + '"'
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, int):
        return str(v)
    f = float(v)
    if math.isinf(f):
        return "inf" if f > 0 else "-inf"
    return repr(f)
