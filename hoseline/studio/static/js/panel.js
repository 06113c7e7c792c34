// The side panel: sliders with exact values, the fittings' numbers, readouts, the sweep timeline,
// files and messages.  It reports what the user changed through callbacks and shows the states.
// A box keeps what the user types only while it is typed in: once given (its change event), the boxes show the
// values in force again, so a value the server refuses does not stay in its box.
import { MessageList } from './message_list.js';

// numbers for display: rounding noise (below 1e-9) shown as 0
const clean = (x) => (Math.abs(x) < 1e-9 ? 0 : Number(x));
const fmt = (x, digits = 4) => (x === null || x === undefined ? '—' : clean(x).toPrecision(digits));
const PENDING = '… (when the drag pauses)';  // a readout the server sends once a drag pauses (studio/server.py)
const exact = (x) => String(Number(clean(x).toFixed(6)));  // in the number boxes: up to 1e-6
const norm = (v) => Math.hypot(...v);
const vector = (v, unit) => `${fmt(norm(v))} ${unit} [${v.map((x) => fmt(x, 3)).join(', ')}]`;

/** A slider's scale: position 0..1000 <-> value, linear or logarithmic between low and high. */
function scale(low, high, logarithmic) {
  return logarithmic
    ? { toValue: (p) => low * (high / low) ** (p / 1000), toPosition: (v) => (1000 * Math.log(v / low)) / Math.log(high / low) }
    : { toValue: (p) => low + ((high - low) * p) / 1000, toPosition: (v) => (1000 * (v - low)) / (high - low) };
}

/** The slider ranges round the values a session starts with. */
function ranges(state) {
  const h = state.hose;
  return {
    length: scale(0.5 * h.length, 2 * h.length, false),
    twist: scale(-360, 360, false),
    torsion_factor: scale(Math.min(0.1, h.torsion_factor / 10), Math.max(100, h.torsion_factor * 10), true),
    bending_stiffness: scale(h.bending_stiffness / 10, h.bending_stiffness * 10, true),
    mass_per_length: scale(0, Math.max(1, 4 * h.mass_per_length), false),
  };
}

const sliderValue = (state, key) => (key === 'twist' ? state.twist : state.hose[key]);

export class Panel {
  /**
   * on: { slider(key, value), typed(fitting, field, [x, y, z]), segments(count), clearance(obstacle, mm), pose(index),
   *       play(), place(), files(FileList), runSweep() }
   */
  constructor(on) {
    this.on = on;
    this.scales = null;
    this.messages = new MessageList(document.getElementById('messages'), document.getElementById('status'));
    this.editing = new Set();  // inputs typed or slid in and not yet given
    const panel = document.getElementById('panel');
    panel.addEventListener('input', (event) => this.editing.add(event.target));
    panel.addEventListener('change', (event) => this.editing.delete(event.target), true);  // before the input's own
    for (const div of document.querySelectorAll('.slider')) {
      const key = div.dataset.key;
      const [range, number] = div.querySelectorAll('input');
      range.min = 0; range.max = 1000; range.step = 1;
      range.addEventListener('input', () => {
        const value = this.scales[key].toValue(Number(range.value));
        number.value = exact(value);
        on.slider(key, value);
      });
      number.addEventListener('change', () => {
        const value = this.finite(number, div.querySelector('label').textContent);
        if (value !== null) on.slider(key, value);
      });
    }
    for (const row of document.querySelectorAll('table.fittings tr[data-fitting]')) this.typedRow(row);
    const segments = document.getElementById('segments');
    segments.addEventListener('change', () => {
      const count = this.finite(segments, 'Segments');
      if (Number.isInteger(count)) on.segments(count); else if (count !== null) this.refuse('Segments: give a whole number');
    });
    document.getElementById('place-again').addEventListener('click', () => on.place());
    const pose = document.getElementById('pose');
    pose.addEventListener('input', () => on.pose(Number(pose.value)));
    document.getElementById('play').addEventListener('click', () => on.play());
    document.getElementById('run-sweep').addEventListener('click', () => on.runSweep());
    document.getElementById('open').addEventListener('change', (event) => on.files(event.target.files));
  }

  /** Send the values typed in a row of the fittings table (three numbers) as a fitting's or clip's tip or direction;
   * a direction of length zero is refused. */
  typedRow(row) {
    const name = row.querySelector('th').textContent;
    for (const input of row.querySelectorAll('input')) {
      input.addEventListener('change', () => {
        const values = [...row.querySelectorAll('input')].map((box, k) => this.finite(box, `${name} ${'xyz'[k]}`));
        if (values.includes(null)) return;
        if (row.dataset.field === 'direction' && Math.hypot(...values) === 0) {
          this.refuse(`${name}: 0, 0, 0 points nowhere: give a direction (of any length but zero)`);
        } else {
          this.on.typed(row.dataset.fitting, row.dataset.field, values);
        }
      });
    }
  }

  /** The number in a box, or null when it holds none (a box of type number reads '' for nan, inf or 1e999): the box
   * then shows the value in force again and the message names it. */
  finite(input, name) {
    const value = input.value.trim() === '' ? NaN : Number(input.value);
    if (Number.isFinite(value)) return value;
    this.refuse(`${name}: must be a finite number`);
    return null;
  }

  /** Say why a typed value is refused and show the values in force again. */
  refuse(text) {
    this.message(text, true, -1);
    if (this.shown) this.show(this.shown);
  }

  /** Rows of the fittings table for the clips: the point (mm) and, for a clip that holds it, the direction. */
  clipRows(clips) {
    const table = document.querySelector('table.fittings');
    table.querySelectorAll('tr[data-clip]').forEach((row) => row.remove());
    clips.forEach((clip, k) => {
      for (const field of clip.kind === 'ball' ? ['point'] : ['point', 'direction']) {
        const row = document.createElement('tr');
        Object.assign(row.dataset, { fitting: `clip${k}`, field, clip: k });
        const label = document.createElement('th');
        label.textContent = `clip ${clip.name || k + 1} (${clip.kind}) ${field === 'point' ? 'point, mm' : 'direction'}`;
        row.append(label, ...[0, 1, 2].map(() => {
          const cell = document.createElement('td');
          cell.append(Object.assign(document.createElement('input'), { type: 'number', step: 'any' }));
          return cell;
        }));
        table.append(row);
        this.typedRow(row);
      }
    });
  }

  /** A new session: slider ranges round its values, the timeline for its sweep. */
  start(session, state) {
    this.clipRows(state.clips);
    this.scales = ranges(state);
    document.getElementById('problem-name').textContent = session.name;
    const timeline = document.getElementById('timeline');
    timeline.hidden = !session.sweep;
    if (session.sweep) {
      const pose = document.getElementById('pose');
      pose.max = session.sweep.poses - 1;
      pose.value = 0;
    }
    this.session = session;
    this.obstacleList(session.obstacles);
  }

  /** One row per obstacle: its name, size and the clearance required to it (editable). */
  obstacleList(obstacles) {
    document.getElementById('obstacle-section').hidden = !obstacles.length;
    document.getElementById('obstacle-list').replaceChildren(...obstacles.map((obstacle) => {
      const tr = document.createElement('tr');
      tr.dataset.obstacle = obstacle.id;
      const name = document.createElement('td');
      name.textContent = `${obstacle.name} (${obstacle.triangles} triangles)`;
      const input = document.createElement('input');
      Object.assign(input, { type: 'number', min: 0, step: 'any', value: exact(obstacle.required) });
      input.addEventListener('change', () => {
        const value = this.finite(input, `${obstacle.name}: the required clearance`);
        if (value !== null && value >= 0) this.on.clearance(obstacle.id, value);
        else if (value !== null) this.refuse(`${obstacle.name}: the required clearance is a distance of 0 mm or more`);
      });
      const cell = document.createElement('td');
      cell.append(input);
      tr.append(name, cell);
      return tr;
    }));
  }

  /** Show a state message: values, fittings, readouts. */
  show(state) {
    this.shown = state;
    for (const div of document.querySelectorAll('.slider')) {
      const key = div.dataset.key;
      const [range, number] = div.querySelectorAll('input');
      const value = sliderValue(state, key);
      if (!this.editing.has(range)) range.value = Math.round(this.scales[key].toPosition(value));
      if (!this.editing.has(number)) number.value = exact(value);
    }
    const segments = document.getElementById('segments');
    if (!this.editing.has(segments)) segments.value = state.hose.segments;
    for (const row of document.querySelectorAll('#obstacle-list tr')) {
      const near = state.readouts.min_clearance[Number(row.dataset.obstacle)];
      const input = row.querySelector('input');
      if (near && !this.editing.has(input)) input.value = exact(near.required);
    }
    for (const row of document.querySelectorAll('table.fittings tr[data-fitting]')) {
      const fitting = row.dataset.clip === undefined ? state.fittings[row.dataset.fitting] : state.clips[Number(row.dataset.clip)];
      if (!fitting) continue;
      const values = row.dataset.field === 'point' ? fitting.point : direction(row.dataset.fitting, fitting.quaternion);
      row.querySelectorAll('input').forEach((input, k) => {
        if (!this.editing.has(input)) input.value = exact(values[k]);
      });
    }
    if (state.pose !== null && this.session && this.session.sweep) {
      const pose = document.getElementById('pose');
      if (document.activeElement !== pose) pose.value = state.pose;
      document.getElementById('pose-label').textContent = poseLabel(this.session.sweep, state.pose);
    }
    this.readouts(state);
  }

  /** The readouts table; those the server left pending during a drag (readouts.pending) show PENDING, greyed,
   * until its "readouts" message comes: never a stale value. */
  readouts(state) {
    const r = state.readouts, rows = [], pending = new Set(r.pending);
    for (const near of r.min_clearance) {
      const ok = near.distance >= near.required;
      rows.push([`clearance to ${near.name}`, `${fmt(near.distance)} mm (required ${fmt(near.required)}) at s = ${fmt(near.s)} mm`, ok]);
    }
    if (!r.min_clearance.length) rows.push(['clearance', 'no obstacles', null]);
    const warned = (readout) => r.warnings.filter((w) => w.readout === readout).map((w) => w.text);
    const limit = r.bend_limit, bendWarnings = warned('min_bend_radius');
    rows.push(['min bend radius', [`${fmt(r.min_bend_radius)} mm (${limit.given ? 'minimum' : 'typical minimum'} ${fmt(limit.radius)})`,
      ...bendWarnings], !bendWarnings.length, 'min_bend_radius']);
    rows.push(['hose length', r.overall_length === null ? `${fmt(r.free_length)} mm`
      : [`free ${fmt(r.free_length)} mm`, `overall ${fmt(r.overall_length)} mm (fittings included)`], null]);
    for (const end of ['start', 'end']) {
      const reactionWarnings = warned(`${end}_reaction`);
      rows.push([`${end} reaction`, [vector(r[`${end}_force`], 'N'), vector(r[`${end}_moment`], 'N·mm'), ...reactionWarnings],
        reactionWarnings.length ? false : null, `${end}_reaction`]);
    }
    const gapPending = pending.has('min_gap');
    for (const c of r.contacts) {
      const touching = c.total_force.some((v) => v !== 0);  // a point contact lies on no length
      const gap = gapPending ? PENDING : c.min_gap === null ? 'far' : `${fmt(c.min_gap, 4)} mm`;
      rows.push([`contact with ${c.name}`, touching
        ? [vector(c.total_force, 'N'), `${c.length_in_contact > 0 ? `lying on ${fmt(c.length_in_contact)} mm` : 'at a point'}, least gap ${gap}`]
        : `not touching (least gap ${gap})`, gapPending ? 'pending' : null]);
    }
    state.clips.forEach((clip, k) => rows.push([`clip ${clip.name || k + 1} (${clip.kind})`,
      [vector(clip.force, 'N'), ...(clip.kind === 'ball' ? [] : [vector(clip.moment, 'N·mm')]), `at s = ${fmt(clip.arc_length)} mm`], null]));
    rows.push(['max twisting moment', `${fmt(r.max_twisting_moment)} N·mm`, null]);
    rows.push(['lock angle (placement)', `${fmt(r.lock_angle)}°`, null]);
    rows.push(['single-plane offset', r.single_plane_offset === null ? 'undefined (parallel directions)' : `${fmt(r.single_plane_offset)} mm`, null]);
    rows.push(['stability margin', pending.has('stability_margin') ? PENDING : `${fmt(r.stability_margin)} N/rad²`,
      pending.has('stability_margin') ? 'pending' : r.stability_margin >= 0, 'stability_margin']);
    const comparison = state.comparison;
    const known = comparison && !comparison.failed;
    const checked = known && comparison.unique !== null;  // null: a search could not be followed, not known
    rows.push(['unique (placement)', checked ? (comparison.unique ? 'yes' : 'no: another stable shape exists') : 'not checked', checked ? comparison.unique : null]);
    if (state.step) rows.push(['last step', `${state.step.iterations} Newton iterations, ${fmt(1000 * state.step.seconds, 2)} ms, moved ${fmt(state.step.movement, 3)} mm`, null]);
    const table = document.getElementById('readouts');
    table.replaceChildren(...rows.map(([name, value, ok, readout]) => {
      const tr = document.createElement('tr');
      if (readout) tr.dataset.readout = readout;
      const th = document.createElement('td'); th.textContent = name;
      const td = document.createElement('td');
      [value].flat().forEach((line, k) => td.append(...(k ? [document.createElement('br')] : []), line));
      if (ok !== null) td.className = ok === 'pending' ? 'pending' : ok ? 'good' : 'bad';
      tr.append(th, td);
      return tr;
    }));
  }

  /** The badge: is the shape shown what a fresh placement gives? */
  badge(comparison) {
    const badge = document.getElementById('badge');
    if (!comparison) {
      badge.className = 'badge pending'; badge.textContent = 'placement: checking'; badge.title = '';
    } else if (comparison.failed) {
      badge.className = 'badge differs'; badge.textContent = 'a fresh placement fails here'; badge.title = comparison.failed;
    } else if (comparison.same) {
      badge.className = 'badge same'; badge.textContent = 'same as a fresh placement';
      badge.title = 'placing this problem afresh from the straight hose gives the shape shown';
    } else {
      const saved = comparison.saved;
      const signed = (x) => `${x >= 0 ? '+' : '−'}${fmt(Math.abs(x), 4)}°`;
      badge.className = 'badge differs';
      badge.textContent = `a fresh placement differs by ${fmt(comparison.distance, 3)} mm`;
      const why = comparison.clocking > 1e-6
        ? `the end fitting is clocked ${fmt(comparison.clocking, 3)}° from where a fresh assembly locks it: the hose was moved after assembly (it keeps its locked twist). "Place again" assembles it here.`
        : 'same fittings, another shape: the path reached another branch. "Place again" gives the placement\'s branch.';
      const clipTwists = (saved && saved.clip_twists || []).map((twist, k) => [k, twist]).filter(([, twist]) => twist !== 0)
        .map(([k, twist]) => `clip ${k + 1} ${signed(twist)}`);
      const clipsSaved = clipTwists.length ? ` Each fixed clip's twist too: ${clipTwists.join(', ')}.` : '';
      const file = !saved ? ''
        : saved.same ? ` The saved file holds the twist at assembly that places the hose as shown: ${fmt(saved.twist)}° (${signed(saved.twist_change)} on the twist as set; its fresh placement is ${fmt(saved.distance, 2)} mm from the shape shown).${clipsSaved}`
          : ` No twist at assembly reproduces the shape shown (${saved.failed ? `the fresh placement with ${fmt(saved.twist)}° fails` : `the nearest, ${fmt(saved.twist)}° (${signed(saved.twist_change)}), places it ${fmt(saved.distance, 3)} mm off`}): "Save" asks which to keep.`;
      if (saved && saved.same) badge.textContent += `; saved as shown (twist ${signed(saved.twist_change)})`;
      badge.title = why + file;
    }
  }

  /** Ask which of an IGES file's point labels make the fittings; `use([startTip, startBehind, endTip, endAhead])`. */
  chooseLabels(fileName, labels, use) {
    const form = document.getElementById('labels');
    document.getElementById('labels-file').textContent = fileName;
    const selects = ['start_tip', 'start_behind', 'end_tip', 'end_ahead'].map((name) => form.elements[name]);
    selects.forEach((select, k) => {
      select.replaceChildren(...labels.map((label) => new Option(label, label)));
      select.selectedIndex = Math.min(k, labels.length - 1);
    });
    form.hidden = false;
    form.onsubmit = (event) => { event.preventDefault(); form.hidden = true; use(selects.map((select) => select.value)); };
    document.getElementById('labels-cancel').onclick = () => { form.hidden = true; };
  }

  /** A line in the Messages list and the header (MessageList.add); `seq`: the change an error refuses. */
  message(text, error = false, seq = undefined) {
    this.messages.add(text, error, seq);
  }

  reportLink(url) {
    const link = document.createElement('a');
    link.href = url; link.target = '_blank'; link.textContent = 'open the report';
    document.getElementById('report-link').replaceChildren(link);
  }
}

/** The direction from a fitting into the hose: d3 of the start frame (and of a clip's: along the hose), -d3 of the end frame. */
function direction(name, [w, x, y, z]) {
  const d3 = [2 * (x * z + w * y), 2 * (y * z - w * x), 1 - 2 * (x * x + y * y)];
  return name === 'end' ? d3.map((v) => -v) : d3;
}

function poseLabel(sweep, index) {
  const stage = sweep.stages.find((s) => index >= s.first && index < s.first + s.count) || { name: 'travel', unit: '' };
  return `pose ${index} of ${sweep.poses - 1}: ${stage.name} = ${fmt(sweep.travel[index])} ${stage.unit}`;
}
