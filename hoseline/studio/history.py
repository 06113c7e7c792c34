"""Undo and redo of the studio's edits: the session as it was before each edit, restored whole.

An edit is one gesture of the user: a drag from press to release, a slider pulled, a value typed,
a clearance set, "Place again", a file opened.  The page numbers its gestures and sends the
number with every message (messages.py, "edit"); the first message of a new number records the
session before it is carried out, so a drag of a hundred steps is undone at once.  A file
opened is an edit of its own.  Undo puts back the equilibrium that was shown, exactly (no path
is followed back, so no other branch can be reached), and redo the one undone.

The history lives in the server, with the session: a reloaded page undoes what was done before.
"""

from __future__ import annotations

import copy
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from hoseline.studio.session import Session

LIMIT = 200  # edits kept for undo


class History:
    """The sessions before the edits done (to undo) and after those undone (to redo)."""

    def __init__(self) -> None:
        self.done: list[dict] = []
        self.undone: list[dict] = []
        self.edit: int | None = None  # the gesture whose session before it was recorded last

    def before(self, session: "Session", edit: int | None) -> bool:
        """Record `session` before a change of gesture `edit` (None: a change of its own, e.g. a file opened), unless
        that gesture's was recorded already; True when it was recorded now (forget() takes it back)."""
        if edit is not None and edit == self.edit:
            return False
        self.done.append(_snapshot(session))
        del self.done[:-LIMIT]
        self.undone.clear()
        self.edit = edit
        return True

    def forget(self) -> None:
        """Take back the record made last: its change was refused and the session is as it was."""
        self.done.pop()
        self.edit = None

    def undo(self, session: "Session") -> bool:
        """Put `session` back to before the last edit; True when the page must be sent the session message too."""
        return self._swap(session, self.done, self.undone)

    def redo(self, session: "Session") -> bool:
        """Do the last undone edit again; True when the page must be sent the session message too."""
        return self._swap(session, self.undone, self.done)

    def _swap(self, session: "Session", source: list[dict], target: list[dict]) -> bool:
        """Move the session to the last of `source`, keeping it as it is now at the end of `target`.  The revision
        counts the files opened along the edits, so a restored session of another revision shows another file."""
        if not source:
            return False
        target.append(_snapshot(session))
        restored = source.pop()
        opened = restored["revision"] != session.revision
        vars(session).update(_copied(restored))
        self.edit = None
        return opened


def _snapshot(session: "Session") -> dict:
    """The session's attributes (changes replace them, never change the arrays they hold in place)."""
    return _copied(vars(session))


def _copied(state: dict) -> dict:
    """The attributes `state` with their own tracker and obstacle list (which later changes step on and extend)."""
    copied = dict(state)
    copied["tracker"] = copy.copy(state["tracker"])
    copied["obstacles"] = list(state["obstacles"])
    return copied
