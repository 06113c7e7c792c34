// A busy indicator over the view for the slow actions (placing the hose again, opening a file): it says what the
// page waits for, with a spinner and the progress cursor, until the answer comes.

export class Busy {
  /** container: the element the indicator is put in (over its top right corner). */
  constructor(container) {
    this.element = Object.assign(document.createElement('span'), { id: 'busy', hidden: true });
    container.append(this.element);
    this.waiting = new Map();  // key -> what is waited for
    this.next = 0;
  }

  /** Show `text` (what the page waits for) until the function returned is called. */
  start(text) {
    const key = this.next++;
    this.waiting.set(key, text);
    this.update();
    return () => { this.waiting.delete(key); this.update(); };
  }

  update() {
    const texts = [...this.waiting.values()];
    this.element.hidden = !texts.length;
    this.element.textContent = texts.join(', ');
    document.body.classList.toggle('busy', texts.length > 0);
  }
}
