// The studio page: wires the 3D view, the fittings' gizmo, the panel and the WebSocket together.
// window.studio exposes the state drawn and a promise per seq, for the tests and the benchmark.
import * as THREE from 'three';
import { Connection } from './connection.js';
import { marks } from './marks.js';
import { stationColours } from './colormaps.js';
import { StudioScene } from './scene.js';
import { HoseView } from './hose.js';
import { ObstacleView } from './obstacles.js';
import { FittingsView } from './fittings.js';
import { Panel } from './panel.js';
import { EditHistory } from './history.js';
import { Snapping } from './snapping.js';
import { Measure } from './measure.js';
import { focusOn } from './focus.js';
import { Persisted } from './persist.js';
import { SaveChoice } from './save.js';
import { Busy } from './busy.js';

const view = document.getElementById('view');
const studioScene = new StudioScene(view);
const hose = new HoseView(studioScene.scene);
const obstacles = new ObstacleView(studioScene.scene);
studioScene.keepDrawn(obstacles.group);
const fittings = new FittingsView(studioScene, (name, object) => send(name.startsWith('clip')
  ? { type: 'set', clips: fittings.clipTargets() } : { type: 'set', [name]: FittingsView.target(object) }));
let session = null, state = null, starting = true, playing = false;
const drawnWaiters = [];  // [seq, resolve] waiting for a state at or past seq to be drawn
const latencies = [];  // ms from a user's event to the shape drawn, one per event

const panel = new Panel({
  slider: (key, value) => send(key === 'twist' ? { type: 'set', twist: value } : { type: 'set', hose: { [key]: value } }),
  typed: (name, field, values) => fittings.setTyped(name, field, values),
  pose: (index) => { playing = false; send({ type: 'set', pose: index }); },
  play: () => { playing = !playing; if (playing) send({ type: 'set', pose: nextPose() }); },
  place: () => busyUntilDrawn('placing the hose again', send({ type: 'place' })),
  segments: (count) => busyUntilDrawn('placing the hose again', send({ type: 'segments', segments: count })),
  clearance: (obstacle, required) => send({ type: 'clearance', obstacle, required }),
  files: (files) => upload([...files]),
  runSweep,
});
const busy = new Busy(view);
const connection = new Connection(receive, () => panel.message('the studio server has stopped: start it again and reload', true));
studioScene.awaitedUntil = () => connection.awaitedUntil;  // a frame due while a target is answered waits for it
studioScene.streaming = () => connection.streaming;  // a drag at the frames' rate: drawn at the frames
fittings.afterDrag = () => { if (state && !connection.waiting) fittings.place(state.fittings, state.clips); };
const toolbar = view.querySelector('.toolbar');
const edits = new EditHistory(send, toolbar);
const snapping = new Snapping(fittings, toolbar, view);
const measure = new Measure(studioScene, { hose: hose.group, fitting: fittings.group, obstacle: obstacles.group }, toolbar, view);
const persisted = new Persisted();
let keptSelection = { selected: persisted.kept.selected, mode: persisted.kept.mode };  // put back at the first state
new SaveChoice(document.getElementById('save'), () => state && state.comparison);
let refused = null;  // the seq of the last message the server refused: its state puts a dragged handle back

/** Send a message: a target ('set') waits while another is in flight (Connection.sendTarget). */
function send(message) {
  const tagged = { ...message, edit: edits.edit };
  return message.type === 'set' ? connection.sendTarget(tagged) : connection.send(tagged);
}

/** What the kept camera belongs to: the file (its name) and the session's revision. */
const sessionKey = () => session && `${session.revision} ${session.name}`;

function receive(message) {
  if (message.type === 'session') {
    session = message;
    starting = true;
    obstacles.load(message.obstacles).then(() => { studioScene.forgetLayer(); if (state) fitView(); })
      .catch((error) => panel.message(String(error), true));
  } else if (message.type === 'state') {
    panel.messages.carriedOut(message.seq);
    draw(message);
  } else if (message.type === 'readouts') {  // those a drag's states left pending (studio/server.py)
    if (state) { state.readouts = message.readouts; showSoon(state); }
  } else if (message.type === 'comparison') {
    if (state) { state.comparison = message.comparison; showSoon(state); }
  } else if (message.type === 'error') {
    refused = message.seq;
    panel.message(message.message, true, message.seq);
    playing = false;
  }
}

function draw(message) {
  state = message;
  if (starting) {
    fittings.build(message.hose.outer_diameter, message.clips, message.pieces);
    panel.start(session, message);
    markActive();
  }
  paint();
  fittings.shapeEnds(message.pieces);
  obstacles.place(message.obstacle_poses);
  // a handle dragged past where the hose can follow stops at the last shape reached
  if (message.seq === null ? !connection.waiting
      : (message.seq >= connection.seq && !connection.pending) || message.seq === refused) {
    fittings.place(message.fittings, message.clips, message.seq === refused);
  }
  if (starting) { fitView(); starting = false; restoreSelection(); }
  studioScene.requestRender((drawnAt) => drawn(message.seq, drawnAt));
  for (const event of (message.step && message.step.events) || []) panel.message(event);
  showSoon(message);
  if (playing && message.seq === connection.seq) send({ type: 'set', pose: nextPose() });
}

/** The frame that draws the state answering `seq` was drawn at `drawnAt` (performance.now()). */
function drawn(seq, drawnAt) {
  if (seq === null) return;
  marks.add('drawn', seq, drawnAt);
  for (const sentAt of connection.takeUpTo(seq)) latencies.push(drawnAt - sentAt);
  for (let k = drawnWaiters.length - 1; k >= 0; k--) {
    if (drawnWaiters[k][0] <= seq) { drawnWaiters[k][1](drawnAt); drawnWaiters.splice(k, 1); }
  }
}

/** Show `text` in the busy indicator until the state answering `seq` is drawn. */
function busyUntilDrawn(text, seq) {
  const done = busy.start(text);
  drawnWaiters.push([seq, done]);
}

/** Show a state's numbers in the panel at an animation frame at least PANEL_MS after the last time: during a drag
 * the panel's layout and painting (the CPU's, without a GPU) are done 10 times a second, however many states
 * arrive, and the last state is always shown. */
const PANEL_MS = 100;
let shownSoon = null, shownAt = -Infinity;
function showSoon(message) {
  if (shownSoon === null) {
    setTimeout(() => requestAnimationFrame(() => {
      panel.show(shownSoon);
      panel.badge(shownSoon.comparison);
      shownSoon = null;
      shownAt = performance.now();
    }), Math.max(0, shownAt + PANEL_MS - performance.now()));
  }
  shownSoon = message;
}

/** Draw the hose of the last state in the colour map chosen. */
function paint() {
  const { colours, legend } = stationColours(document.getElementById('colour-map').value, state);
  hose.update(state, colours);
  showLegend(legend);
}

function nextPose() {
  const next = state && state.pose !== null ? state.pose + 1 : 0;
  if (next >= session.sweep.poses - 1) playing = false;
  return Math.min(next, session.sweep.poses - 1);
}

function fitView() {
  const box = obstacles.boundsNear(hose.bounds());
  for (const object of Object.values(fittings.objects)) box.expandByPoint(object.position);
  studioScene.setGround(box);
  if (!persisted.restoreCamera(studioScene, sessionKey())) studioScene.view('iso');
}

function showLegend(legend) {
  const element = document.getElementById('legend');
  element.hidden = !legend;
  if (!legend) return;
  const title = document.createElement('div'); title.textContent = legend.title;
  const bar = document.createElement('div'); bar.className = `bar ${legend.kind}`;
  const ends = document.createElement('div'); ends.className = 'ends';
  for (const text of [legend.low, legend.mid, legend.high]) { const span = document.createElement('span'); span.textContent = text; ends.append(span); }
  element.replaceChildren(title, bar, ends);
}

/** Upload dropped or chosen files: with a .toml among them, the others are kept for it and it is opened last. */
async function upload(files) {
  const done = busy.start(`opening ${files.map((file) => file.name).join(', ')}`);
  try {
    await uploadInOrder(files);
  } finally {
    done();
  }
}

async function uploadInOrder(files) {
  const main = files.filter((file) => file.name.toLowerCase().endsWith('.toml'));
  const ordered = main.length ? [...files.filter((file) => !main.includes(file)).map((file) => [file, true]), ...main.map((file) => [file, false])]
    : files.map((file) => [file, false]);
  for (const [file, store] of ordered) await sendFile(file, store ? '?store=1' : '');
}

/** Post one file; an IGES file without the thesis' labels gets its labels offered to choose from. */
async function sendFile(file, query) {
  try {
    const response = await fetch(`/upload/${encodeURIComponent(file.name)}${query}`, { method: 'POST', body: file });
    const answer = await response.json();
    if (response.ok) panel.message(answer.message); else panel.message(answer.error, true);
    if (answer.labels) {
      panel.chooseLabels(file.name, answer.labels, (chosen) => sendFile(file, `?labels=${encodeURIComponent(chosen.join(','))}`));
    }
  } catch (error) {
    panel.message(`${file.name}: ${error}`, true);
  }
}

async function runSweep() {
  panel.message('running the sweep ...');
  const response = await fetch('/sweep', { method: 'POST' });
  const answer = await response.json();
  if (!response.ok) { panel.message(answer.error, true); return; }
  panel.message('the sweep is done');
  panel.reportLink(answer.report);
  window.open(answer.report, '_blank');
}

document.querySelectorAll('[data-view]').forEach((button) => button.addEventListener('click', () => studioScene.view(button.dataset.view)));
document.querySelectorAll('[data-select]').forEach((button) => button.addEventListener('click', () => {
  fittings.select(button.dataset.select === 'none' ? null : button.dataset.select);
  markActive();
}));
document.querySelectorAll('[data-mode]').forEach((button) => button.addEventListener('click', () => {
  fittings.select(fittings.selected, button.dataset.mode);
  markActive();
}));
/** Look at the selected fitting or clip from where the view looks now (F); with nothing selected, fit everything. */
function focusSelected() {
  const object = fittings.selected && fittings.objects[fittings.selected];
  if (!object || !state) { studioScene.view('fit'); return; }
  focusOn(studioScene, object.position, 10 * state.hose.outer_diameter);
}
function markActive() {
  persisted.keep({ selected: fittings.selected, mode: fittings.gizmo.mode });
  document.querySelectorAll('[data-select]').forEach((b) => b.classList.toggle('active', b.dataset.select === (fittings.selected || 'none')));
  document.querySelectorAll('[data-mode]').forEach((b) => b.classList.toggle('active', b.dataset.mode === fittings.gizmo.mode));
}
window.addEventListener('keydown', (event) => {
  if (event.target.tagName === 'INPUT' || event.target.tagName === 'SELECT') return;
  if (event.key === 'w') fittings.select(fittings.selected, 'translate');
  else if (event.key === 'e') fittings.select(fittings.selected, 'rotate');
  else if (event.key === 'Escape') { fittings.select(null); measure.set(false); }
  else if (event.key === 's') snapping.set(!snapping.on);
  else if (event.key === 'm') measure.set(!measure.active);
  else if (event.key === 'f') focusSelected();
  markActive();
});
document.getElementById('colour-map').addEventListener('change', () => { if (state) { paint(); studioScene.requestRender(); } });

// a click on a fitting selects it for the gizmo
const raycaster = new THREE.Raycaster();
studioScene.renderer.domElement.addEventListener('pointerdown', (event) => {
  if (fittings.gizmo.axis || measure.active) return;  // on the gizmo itself, or picking points to measure
  const rect = event.target.getBoundingClientRect();
  const pointer = new THREE.Vector2(((event.clientX - rect.left) / rect.width) * 2 - 1, -((event.clientY - rect.top) / rect.height) * 2 + 1);
  raycaster.setFromCamera(pointer, studioScene.camera);
  const hit = raycaster.intersectObjects(fittings.group.children, true)[0];
  if (!hit) return;
  fittings.select(fittings.nameOf(hit.object));
  markActive();
});

// files may be dropped anywhere on the page (the browser would otherwise open them in place of the studio)
document.addEventListener('dragover', (event) => { event.preventDefault(); view.classList.add('dropping'); });
document.addEventListener('dragleave', (event) => { if (!event.relatedTarget) view.classList.remove('dropping'); });
document.addEventListener('drop', (event) => { event.preventDefault(); view.classList.remove('dropping'); upload([...event.dataTransfer.files]); });
fittings.select(null, 'translate');
markActive();

// what a reload keeps (persist.js): the camera, colour map, selection, gizmo mode and snapping
studioScene.orbit.addEventListener('change', () => { if (session && !starting) persisted.keepCamera(studioScene, sessionKey()); });
snapping.onChange = () => persisted.keep({ snapping: snapping.settings });
if (persisted.kept.snapping) snapping.settings = persisted.kept.snapping;
const colourMap = document.getElementById('colour-map');
if (persisted.kept.colourMap) colourMap.value = persisted.kept.colourMap;
colourMap.addEventListener('change', () => persisted.keep({ colourMap: colourMap.value }));
/** Select the fitting or clip and gizmo mode kept before a reload, once, when the first state is drawn. */
function restoreSelection() {
  if (!keptSelection) return;
  const { selected, mode } = keptSelection;
  keptSelection = null;
  fittings.select(selected && fittings.objects[selected] ? selected : null, mode || undefined);
  markActive();
}

window.studio = {
  get state() { return state; },
  latencies,
  fittings,
  hose,
  scene: studioScene,
  send,
  /** Resolves with performance.now() when a state at or past `seq` has been drawn. */
  drawn(seq) { return new Promise((resolve) => drawnWaiters.push([seq, resolve])); },
  /** performance.now() when the last message from the server arrived. */
  get receivedAt() { return connection.receivedAt; },
  /** The seq of the last message sent. */
  get seq() { return connection.seq; },
  /** Timestamps of targets sent, states received and frames drawn, for the benchmark (marks.js). */
  marks,
};
