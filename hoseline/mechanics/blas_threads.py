"""One BLAS thread for the solver's small dense algebra.

The dense systems of the solver (contact's KKT fallbacks and stability margins, sweeps' many small
solves, the scans' local fits) are tens to hundreds of unknowns: OpenBLAS's threads only wait for
each other there, and on a loaded two-core machine they made such steps 4-10x slower (measured:
the stability margin with contact 36 ms against 2 ms).  threadpoolctl sets the limit; its
controller scans the loaded libraries when made (about 2 ms), so it is made once.
"""

from __future__ import annotations

from contextlib import AbstractContextManager

from threadpoolctl import ThreadpoolController

_CONTROLLER: list[ThreadpoolController] = []


def one_blas_thread() -> AbstractContextManager:
    """A context in which BLAS (OpenBLAS, MKL) runs on one thread."""
    if not _CONTROLLER:
        _CONTROLLER.append(ThreadpoolController())
    return _CONTROLLER[0].limit(limits=1, user_api="blas")
