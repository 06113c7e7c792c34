// The Messages list and the header's status line.  One line per cause: a message that differs from one already
// listed only in its numbers (a refused drag says so at every pointer move) replaces it, moved to the top with a
// count of how often it came.  An error in the header is taken away once a later change is carried out without one.

const LONGEST = 50;  // lines kept

/** What a message says without its numbers: messages alike but for them have the same cause. */
const causeOf = (text) => text.replace(/[-+]?\d+(\.\d+)?(e[-+]?\d+)?/gi, '#');

export class MessageList {
  constructor(list, status) {
    this.list = list;
    this.status = status;
    this.errorSeq = null;  // seq of the change whose refusal the header shows (undefined: not a change's)
  }

  /** Show `text` at the top of the list and in the header; `error`: in red; `seq`: the change it refuses. */
  add(text, error = false, seq = undefined) {
    const cause = causeOf(text);
    let item = [...this.list.children].find((li) => li.dataset.cause === cause);
    if (item) {
      item.dataset.count = Number(item.dataset.count) + 1;
    } else {
      item = document.createElement('li');
      Object.assign(item.dataset, { cause, count: 1 });
    }
    item.textContent = item.dataset.count > 1 ? `${text} (${item.dataset.count} times)` : text;
    item.className = error ? 'error' : '';
    this.list.prepend(item);
    while (this.list.children.length > LONGEST) this.list.lastChild.remove();
    this.status.textContent = text;
    this.status.className = error ? 'error' : '';
    this.errorSeq = error ? seq : null;
  }

  /** A state answering change `seq` has come without an error: a refusal of an earlier change leaves the header. */
  carriedOut(seq) {
    if (this.errorSeq === null || this.errorSeq === undefined || seq === null || seq <= this.errorSeq) return;
    this.status.textContent = '';
    this.status.className = '';
    this.errorSeq = null;
  }
}
