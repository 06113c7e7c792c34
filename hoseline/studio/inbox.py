"""The solve loop's inbox: messages in order, except that a burst of targets coalesces into the latest.

While the solver works on one step, the page may send many drag events.  A target arriving
while the last waiting message is also a target replaces it (the latest state wins, nothing
queues up); commands ("place again") keep their place in the order.  The count of targets
dropped this way is kept for the tests and the benchmark.
"""

from __future__ import annotations

import asyncio
from collections import deque

from hoseline.studio.messages import Command, Target


class Inbox:
    """Messages waiting for the solver, with consecutive targets merged."""

    def __init__(self) -> None:
        self._waiting: deque[Target | Command] = deque()
        self._arrived = asyncio.Event()
        self.coalesced = 0

    def put(self, message: Target | Command) -> None:
        """Add a message; a target replaces a target waiting at the end."""
        if isinstance(message, Target) and self._waiting and isinstance(self._waiting[-1], Target):
            self._waiting[-1] = _merged(self._waiting[-1], message)
            self.coalesced += 1
        else:
            self._waiting.append(message)
        self._arrived.set()

    async def get(self, timeout: float | None = None) -> Target | Command | None:
        """The next message, or None when none arrived within `timeout` seconds."""
        if not self._waiting:
            try:
                await asyncio.wait_for(self.arrival(), timeout)
            except asyncio.TimeoutError:
                return None
        return self._waiting.popleft()

    async def arrival(self) -> None:
        """Return once a message is waiting (left in the inbox)."""
        while not self._waiting:
            self._arrived.clear()
            await self._arrived.wait()


def _merged(older: Target, newer: Target) -> Target:
    """One target for two: the newer one's values, the older one's where the newer leaves a part out
    (a slider moved while a fitting was dragged: both changes are kept)."""
    fields = {name: getattr(older, name) for name in Target.model_fields}
    fields.update({name: value for name, value in newer if value is not None})
    if older.hose is not None and newer.hose is not None:
        hose = older.hose.model_dump()
        hose.update({key: value for key, value in newer.hose.model_dump().items() if value is not None})
        fields["hose"] = hose
    if newer.pose is None and (newer.start is not None or newer.end is not None or newer.clips is not None):
        fields["pose"] = None  # a fitting or clip dragged after a sweep pose: the drag is the latest word
    return Target.model_validate(fields)
