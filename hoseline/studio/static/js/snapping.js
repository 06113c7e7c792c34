// Snapping of the gizmo's moves and turns to steps (mm, degrees) from where the drag began (a move along the fitting's
// axes in whole steps, a turn in whole steps of angle), switched with a key or the toolbar, and a readout of the
// distance and angle moved since the drag began, shown over the view while dragging.
import * as THREE from 'three';

const fmt = (x) => String(Number(x.toFixed(3)));

export class Snapping {
  /** fittings: the FittingsView, whose gizmo is snapped; toolbar: where its controls go; view: the element the readout
   * lies over; step (mm) and angle (degrees): the snapping steps to start with. */
  constructor(fittings, toolbar, view, { step = 5, angle = 15 } = {}) {
    const gizmo = fittings.gizmo;
    this.gizmo = gizmo;
    fittings.adjust = (object) => this.snap(object);
    this.on = false;
    this.button = Object.assign(document.createElement('button'), { id: 'snap', textContent: 'Snap', title: 'snap moves and turns to steps (S)' });
    this.stepBox = Object.assign(document.createElement('input'), { id: 'snap-step', type: 'number', min: 0, step: 'any', value: step, title: 'snapping step of a move, mm' });
    this.angleBox = Object.assign(document.createElement('input'), { id: 'snap-angle', type: 'number', min: 0, step: 'any', value: angle, title: 'snapping step of a turn, degrees' });
    const unit = (text) => Object.assign(document.createElement('span'), { className: 'unit', textContent: text });
    toolbar.append(Object.assign(document.createElement('span'), { className: 'separator' }),
      this.button, this.stepBox, unit('mm'), this.angleBox, unit('°'));
    this.button.addEventListener('click', () => this.set(!this.on));
    for (const box of [this.stepBox, this.angleBox]) box.addEventListener('change', () => this.set(this.on));
    this.readout = Object.assign(document.createElement('div'), { id: 'drag-readout', hidden: true });
    view.append(this.readout);
    gizmo.addEventListener('mouseDown', () => this.begin());
    gizmo.addEventListener('objectChange', () => this.moved());
    gizmo.addEventListener('mouseUp', () => { this.readout.hidden = true; });
  }

  /** Switch snapping on or off (with the steps in the boxes; a step of 0 or less snaps nothing). */
  set(on) {
    this.on = on;
    const step = Number(this.stepBox.value), angle = Number(this.angleBox.value);
    this.step = on && step > 0 ? step : null;
    this.gizmo.setRotationSnap(on && angle > 0 ? THREE.MathUtils.degToRad(angle) : null);
    this.button.classList.toggle('active', on);
    if (this.onChange) this.onChange();
  }

  /** The steps as kept across a reload: {on, step, angle}. */
  get settings() { return { on: this.on, step: Number(this.stepBox.value), angle: Number(this.angleBox.value) }; }

  set settings({ on, step, angle }) {
    this.stepBox.value = step;
    this.angleBox.value = angle;
    this.set(on);
  }

  begin() {
    const object = this.gizmo.object;
    if (!object) return;
    this.start = { position: object.position.clone(), quaternion: object.quaternion.clone() };
    this.moved();
  }

  /** Put a moved object at whole steps from where the drag began, along the axes of its frame then. */
  snap(object) {
    if (!this.step || !this.start || this.gizmo.mode !== 'translate') return;
    const inverse = this.start.quaternion.clone().invert();
    const offset = object.position.clone().sub(this.start.position).applyQuaternion(inverse);
    offset.set(...offset.toArray().map((x) => Math.round(x / this.step) * this.step));
    object.position.copy(this.start.position).add(offset.applyQuaternion(this.start.quaternion));
  }

  /** Show how far the dragged object is from where the drag began: distance (mm) with its components, angle (°). */
  moved() {
    const object = this.gizmo.object;
    if (!object || !this.start || !this.gizmo.dragging) return;
    const offset = object.position.clone().sub(this.start.position);
    const angle = THREE.MathUtils.radToDeg(this.start.quaternion.angleTo(object.quaternion));
    this.readout.textContent = this.gizmo.mode === 'rotate'
      ? `turned ${fmt(angle)}°`
      : `moved ${fmt(offset.length())} mm [${offset.toArray().map(fmt).join(', ')}]`;
    this.readout.hidden = false;
  }
}
