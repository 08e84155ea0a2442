"""Progress bars with an estimate, on stderr (issue 40: every job over ~2 s says how long).

One helper for the long steps of ``optimize`` (its generations, then the members' reference
checks), ``scale`` and the sweep's plot: a tqdm bar (imported only when a bar is drawn), its
count set to what the job reports done, the estimate tqdm's (the rate so far). Disabled, it
costs nothing and prints nothing.
"""

from __future__ import annotations

from collections.abc import Callable, Iterator
from contextlib import contextmanager


@contextmanager
def bar(total: int, desc: str, unit: str, enabled: bool = True) -> Iterator[Callable[[int], None]]:
    """A progress bar of ``total`` ``unit`` on stderr, with its estimate; yields
    ``done(n)``, which sets the count to ``n`` (monotone: a smaller n is ignored)."""
    if not enabled or total <= 0:
        yield lambda _n: None
        return
    from tqdm import tqdm

    with tqdm(total=total, desc=desc, unit=unit) as b:  # left on stderr: how long it took

        def done(n: int) -> None:
            n = min(int(n), total)
            if n > b.n:
                b.update(n - b.n)

        yield done
