// Undo and redo (Ctrl+Z, Ctrl+Shift+Z or Ctrl+Y), and the numbering of the user's gestures by which the server
// groups the changes into edits (hoseline/studio/history.py): a drag from press to release, a slider pulled, a value
// typed and committed is one edit.  The browser's own text undo is kept out of the page: it would put an old value
// back into a number box, to be sent at the next change as if the user had typed it.

/** 'undo', 'redo' or null for a keydown event. */
function undoKey(event) {
  if (!(event.ctrlKey || event.metaKey) || event.altKey) return null;
  const key = event.key.toLowerCase();
  if (key === 'z') return event.shiftKey ? 'redo' : 'undo';
  if (key === 'y' && !event.shiftKey) return 'redo';
  return null;
}

export class EditHistory {
  /** send(message): sends {type: 'undo'} or {type: 'redo'} to the server; toolbar: where their buttons go. */
  constructor(send, toolbar) {
    this.edit = 0;  // the number of the gesture going on, sent with every message
    toolbar.append(Object.assign(document.createElement('span'), { className: 'separator' }));
    for (const [which, text, title] of [['undo', 'Undo', 'undo the last edit (Ctrl+Z)'], ['redo', 'Redo', 'redo (Ctrl+Shift+Z)']]) {
      const button = Object.assign(document.createElement('button'), { id: which, textContent: text, title });
      button.addEventListener('click', () => send({ type: which }));
      toolbar.append(button);
    }
    const next = () => { this.edit += 1; };
    window.addEventListener('pointerdown', next, true);
    window.addEventListener('keydown', (event) => {
      const which = undoKey(event);
      if (!which) { next(); return; }
      event.preventDefault();
      send({ type: which });
    }, true);
    // a committed value is an edit of its own: new numbers before its handlers send it and after
    window.addEventListener('change', next, true);
    window.addEventListener('change', next);
    window.addEventListener('beforeinput', (event) => {
      if (event.inputType === 'historyUndo' || event.inputType === 'historyRedo') event.preventDefault();
    }, true);
  }
}
