"""Long jobs say how long they will take, and the longest ask first (one rule for all).

Every command whose work is estimated before it starts — FEM solves over many currents
(``torque --method fem``), a sweep's designs and chunks, ``--verify-top``'s FEM solves —
passes its estimate to ``announce``:

* above ``ANNOUNCE_AFTER_S`` (30 s) it prints one line on stderr: what, how many, about how
  long, from what rate, before any work starts;
* above ``ASK_AFTER_S`` (10 min) it refuses without ``--yes`` (one line, exit 2), the
  estimate in the message, so that nobody waits an hour for a job they did not mean.

The limits are documented here and in the commands' ``--yes`` help; a leaf module (no heavy
import), so the commands import it at the top.
"""

from __future__ import annotations

import sys

from mrclutch.cli.errors import CLIError

#: s: work estimated longer than this is announced on stderr before it starts.
ANNOUNCE_AFTER_S = 30.0
#: s: work estimated longer than this runs only with --yes.
ASK_AFTER_S = 600.0


def duration(seconds: float) -> str:
    """``seconds`` as a person reads it: s under 2 min, min under 2 h, else h."""
    if seconds < 120:
        return f"{seconds:.0f} s"
    if seconds < 7200:
        return f"{seconds / 60:.0f} min"
    return f"{seconds / 3600:.1f} h"


def announce(command: str, what: str, seconds: float, basis: str, yes: bool) -> bool:
    """Say ``what`` will take about ``seconds`` (from ``basis``) when above
    ANNOUNCE_AFTER_S; refuse (CLIError) above ASK_AFTER_S without ``yes``. True when it
    said something."""
    if seconds > ASK_AFTER_S and not yes:
        raise CLIError(f"{what}, about {duration(seconds)} ({basis}), more than "
                       f"{duration(ASK_AFTER_S)}; add --yes to run it")  # fmt: skip
    if seconds > ANNOUNCE_AFTER_S:
        print(f"mrclutch {command}: {what}, about {duration(seconds)} ({basis}); going on",
              file=sys.stderr)  # fmt: skip
        return True
    return False
