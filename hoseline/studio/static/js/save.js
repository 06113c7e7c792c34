// Saving the problem file.  The file the studio writes solves to the shape shown (hoseline/studio/saving.py: the end
// fitting's and each fixed clip's twist at assembly that a fresh placement needs, checked by placing it).  Where that
// check fails (a hose that is not round with its start fitting turned, another branch) the user chooses:
// "as moved" (that twist, solving as close to the shape shown as the file can) or "re-assembled" (the twist as set:
// the shape "Place again" gives).

const fmt = (x) => (x === null || x === undefined ? '—' : String(Number(x.toPrecision(4))));

export class SaveChoice {
  /** link: the page's save link; comparison(): the last state's comparison (null while a fresh placement runs). */
  constructor(link, comparison) {
    this.link = link;
    this.form = Object.assign(document.createElement('p'), { id: 'save-choice', hidden: true });
    link.parentElement.after(this.form);
    link.addEventListener('click', (event) => {
      const known = comparison();
      if (known && known.saved && known.saved.same) { this.form.hidden = true; return; }  // it solves as shown
      event.preventDefault();
      if (known) { this.ask(known); return; }
      this.form.replaceChildren('checking that the saved file solves to the shape shown ...');
      this.form.hidden = false;
      this.waitFor(comparison);
    });
  }

  /** Once the server has placed the problem afresh (the comparison of the next state), save or ask. */
  waitFor(comparison) {
    const known = comparison();
    if (!known) { setTimeout(() => this.waitFor(comparison), 100); return; }
    this.form.hidden = true;
    if (known.saved && known.saved.same) this.link.click(); else this.ask(known);
  }

  ask(comparison) {
    const saved = comparison.saved || { failed: comparison.failed, twist: null };  // no fresh placement at all
    const moved = saved.failed ? `(a fresh placement fails: ${saved.failed})` : `solves ${fmt(saved.distance)} mm off the shape shown`;
    const choice = (way, text, title) => Object.assign(document.createElement('a'), {
      href: `/problem.toml?as=${way}`, download: 'problem.toml', textContent: text, title, className: `save-${way}`,
    });
    const assembled = comparison.failed ? 'a fresh placement fails' : `the shape "Place again" gives, ${fmt(comparison.distance)} mm off the shape shown`;
    this.form.replaceChildren(
      'No problem file reproduces the shape shown. Save ',
      choice('moved', `as moved (twist ${fmt(saved.twist)}°)`, moved), ` — ${moved}; or `,
      choice('assembled', 're-assembled', assembled), ` — ${assembled}.`,
    );
    this.form.hidden = false;
    this.form.querySelectorAll('a').forEach((a) => a.addEventListener('click', () => { this.form.hidden = true; }));
  }
}
