"""Progress bars with an estimate, on stderr (issue 40: every job over ~2 s says how long).

One helper for the long steps of ``optimize`` (its generations, then the members' reference
checks), ``scale`` and the sweep's plot: a tqdm bar (imported only when a bar is drawn), its
count set to what the job reports done, the estimate tqdm's (the rate so far). Disabled, it
costs nothing and prints nothing.
"""

from __future__ import annotations

import sys
from collections.abc import Callable, Iterator
from contextlib import contextmanager


def _nothing(_n: int, note: str | None = None) -> None:
    pass


@contextmanager
def bar(total: int, desc: str, unit: str, enabled: bool = True) -> Iterator[Callable[..., None]]:
    """A progress bar of ``total`` ``unit`` on stderr, with its estimate; yields
    ``done(n, note=None)``, which sets the count to ``n`` (monotone: a smaller n is
    ignored) and writes ``note``, when given, on its own line above the bar."""
    if not enabled or total <= 0:
        yield _nothing
        return
    from tqdm import tqdm

    with tqdm(total=total, desc=desc, unit=unit) as b:  # left on stderr: how long it took

        def done(n: int, note: str | None = None) -> None:
            if note is not None:
                b.write(note, file=sys.stderr)
            n = min(int(n), total)
            if n > b.n:
                b.update(n - b.n)

        yield done
