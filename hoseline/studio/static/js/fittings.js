// The two fittings and the clips: each an object whose axes are its frame (x = d1, y = d2, z = d3 along
// the hose; the end fitting without its twist), a fitting drawn as a short body behind the tip, a clip
// as a ring round the hose at its point (a ball clip, which holds the position only, as a sphere).
// With end fittings the objects 'start' and 'end' are the ports, and each fitting is drawn as a rigid
// tube along its centreline from the port to the outlet (in the port's frame, so it turns with the port).
// Objects are kept by name ('start', 'end', 'clip0', 'clip1', ...).  A TransformControls gizmo moves or
// turns the selected one; every change of it is a drag event.
import * as THREE from 'three';
import { TransformControls } from 'three/addons/controls/TransformControls.js';

// pointerrawupdate (where the page is a secure context, as on 127.0.0.1) is dispatched as soon as the browser takes a
// move in; pointermove waits for the next animation frame (in chromium at 60 Hz some 4 ms later, median)
const RAW_MOVES = 'onpointerrawupdate' in window;

/** The gizmo, its drag following pointerrawupdate where the browser has it (pointermove then ignored), else
 * pointermove. */
class Gizmo extends TransformControls {
  constructor(camera, element) {
    super(camera, element);
    if (!RAW_MOVES) return;
    element.addEventListener('pointerrawupdate', (event) => {
      if (this.enabled) this.pointerMove(this._getPointer(event), true);  // as the gizmo's own pointermove handler
    });
  }

  pointerMove(pointer, raw = false) {
    if (raw === RAW_MOVES) super.pointerMove(pointer);
  }
}

const COLOURS = { start: 0x2f7bd8, end: 0xd84f2f, clip: 0x8a5cc2 };
const DRAWN_ALONE_MS = 50;  // a dragged fitting whose state has not come by then is drawn without it

export class FittingsView {
  /** onDrag(name, object): the fitting `name` was moved by the gizmo (or by drag()). */
  constructor(studioScene, onDrag) {
    this.studioScene = studioScene;
    this.onDrag = onDrag;
    this.objects = {};
    this.group = new THREE.Group();
    studioScene.scene.add(this.group);
    for (const name of ['start', 'end']) {
      const object = new THREE.Group();
      object.name = `${name} fitting`;
      this.objects[name] = object;
      this.group.add(object);
    }
    this.gizmo = new Gizmo(studioScene.camera, studioScene.renderer.domElement);
    this.gizmo.setSpace('local');
    this.gizmo.setSize(0.8);
    studioScene.scene.add(this.gizmo.getHelper());
    // during a drag the fitting is drawn with the state answering it, not before: a frame drawn meanwhile (in
    // software, without a GPU, it takes the CPU for tens of ms) would hold up the server's step; only a slow
    // answer lets the fitting be drawn alone, DRAWN_ALONE_MS after the move
    this.gizmo.addEventListener('change', () => {
      if (this.dragging) studioScene.requestRenderAfter(DRAWN_ALONE_MS); else studioScene.requestRender();
    });
    this.gizmo.addEventListener('dragging-changed', (event) => {
      studioScene.orbit.enabled = !event.value;
      this.dragging = event.value;
      if (event.value) studioScene.dragged();  // drawn at the drag's resolution before its first target goes
      if (!event.value && this.afterDrag) this.afterDrag();
      studioScene.requestRender();
    });
    this.gizmo.addEventListener('objectChange', () => {
      if (this.adjust) this.adjust(this.objects[this.selected]);  // snapping (snapping.js), before it is sent
      this.onDrag(this.selected, this.objects[this.selected]);
      studioScene.dragged();
    });
    this.dragging = false;
    this.selected = null;
  }

  /** Size the fitting bodies to the hose (outer diameter, mm), draw the end fittings of a state message's
   * `pieces` and make one object per clip of its `clips` (kind 'ball' a sphere, the others a ring); called when a
   * session starts. */
  build(outerDiameter, clips = [], pieces = {}) {
    for (const name of Object.keys(this.objects).filter((key) => key.startsWith('clip'))) {
      this.group.remove(this.objects[name]);
      delete this.objects[name];
    }
    if (this.selected && !this.objects[this.selected]) this.select(null);
    clips.forEach((clip, k) => {
      const object = new THREE.Group();
      object.name = `clip ${k}${clip.name ? ` ${clip.name}` : ''}`;
      const material = new THREE.MeshStandardMaterial({ color: COLOURS.clip, roughness: 0.5, metalness: 0.2 });
      const shape = clip.kind === 'ball'
        ? new THREE.SphereGeometry(0.9 * outerDiameter, 24, 16)
        : new THREE.TorusGeometry(0.8 * outerDiameter, 0.25 * outerDiameter, 12, 32);  // in the xy plane: round d3
      const body = new THREE.Mesh(shape, material);
      body.name = `clip ${k} body`;
      if (clip.kind === 'ball') { material.transparent = true; material.opacity = 0.45; }
      object.add(body);
      if (clip.kind !== 'ball') object.add(new THREE.AxesHelper(2.5 * outerDiameter));
      this.objects[`clip${k}`] = object;
      this.group.add(object);
    });
    this.outerDiameter = outerDiameter;
    this.shapeEnds(pieces, true);
  }

  /** Draw each end as its fitting of `pieces` ({start, end}: centreline in the port's frame, mm, and radius), or
   * as a short body behind the tip where there is none; only when they changed (a fresh placement may give the
   * ports another roll) or `always`. */
  shapeEnds(pieces = {}, always = false) {
    const key = JSON.stringify(pieces, (_, v) => (typeof v === 'number' ? Math.round(v * 1e6) : v));  // to 1e-6 mm
    if (!always && key === this.piecesKey) return;
    this.piecesKey = key;
    const outerDiameter = this.outerDiameter;
    for (const name of ['start', 'end']) {
      const object = this.objects[name];
      object.traverse((child) => { if (child.geometry) { child.geometry.dispose(); child.material.dispose(); } });
      object.clear();
      const material = new THREE.MeshStandardMaterial({ color: COLOURS[name], roughness: 0.4, metalness: 0.3 });
      if (pieces[name]) {
        object.add(...FittingsView.piece(pieces[name], material, `${name} fitting piece`),
          new THREE.AxesHelper(4 * outerDiameter));
        continue;
      }
      const sign = name === 'start' ? -1 : 1;  // the fitting lies behind the tip: before the start, after the end
      const length = 3 * outerDiameter;
      const body = new THREE.Mesh(new THREE.CylinderGeometry(0.75 * outerDiameter, 0.75 * outerDiameter, length, 24), material);
      body.rotation.x = Math.PI / 2;  // cylinder axis (y) onto z
      body.position.z = (sign * length) / 2;
      body.name = `${name} fitting body`;
      object.add(body, new THREE.AxesHelper(4 * outerDiameter));
    }
  }

  /** Put the fittings and clips where a state message has them, except one the user is dragging (unless `dragged`). */
  place(fittings, clips = [], dragged = false) {
    const all = { ...fittings, ...Object.fromEntries(clips.map((clip, k) => [`clip${k}`, clip])) };
    for (const [name, fitting] of Object.entries(all)) {
      if (!this.objects[name]) continue;
      if (this.dragging && name === this.selected && !dragged) continue;
      const [w, x, y, z] = fitting.quaternion;
      this.objects[name].position.fromArray(fitting.point);
      this.objects[name].quaternion.set(x, y, z, w);
    }
  }

  /** The clips' targets for the server, in the problem's order. */
  clipTargets() {
    return Object.keys(this.objects).filter((name) => name.startsWith('clip'))
      .sort((a, b) => Number(a.slice(4)) - Number(b.slice(4))).map((name) => FittingsView.target(this.objects[name]));
  }

  /** The name of the fitting or clip an object drawn belongs to (null: none). */
  nameOf(object) {
    while (object && object.parent !== this.group) object = object.parent;
    return Object.keys(this.objects).find((name) => this.objects[name] === object) || null;
  }

  /** Attach the gizmo to 'start', 'end', a clip ('clip0', ...) or nothing (null); mode 'translate' or 'rotate'. */
  select(name, mode) {
    if (mode) this.gizmo.setMode(mode);
    this.selected = name;
    if (name) this.gizmo.attach(this.objects[name]); else this.gizmo.detach();
    this.studioScene.requestRender();
  }

  /** Move fitting `name` by `offset` (mm, world) and turn it by `degrees` about its own `axis` (0 x, 1 y, 2 z),
   * as a gizmo drag would; for typed values, the benchmark and the tests. */
  drag(name, offset = [0, 0, 0], axis = 0, degrees = 0) {
    const object = this.objects[name];
    object.position.add(new THREE.Vector3(...offset));
    const local = new THREE.Vector3(); local.setComponent(axis, 1);
    object.quaternion.multiply(new THREE.Quaternion().setFromAxisAngle(local, THREE.MathUtils.degToRad(degrees)));
    this.onDrag(name, object);
  }

  /** Set fitting or clip `name` to a typed tip (mm) or direction (from the fitting into the hose; a clip's along
   * the hose), turning it the least. */
  setTyped(name, field, values) {
    const object = this.objects[name];
    if (field === 'point') {
      object.position.fromArray(values);
    } else {
      const wanted = new THREE.Vector3(...values).normalize();
      if (name === 'end') wanted.negate();  // the end frame's d3 runs along the hose, out of the end fitting
      const current = new THREE.Vector3(0, 0, 1).applyQuaternion(object.quaternion);
      object.quaternion.premultiply(new THREE.Quaternion().setFromUnitVectors(current, wanted));
    }
    this.onDrag(name, object);
  }

  /** The meshes of a rigid end fitting: a tube of its radius along its centreline (points in the port's frame,
   * mm), a ball at a sharp corner (a centreline of three points: port, vertex, outlet). */
  static piece({ centreline, radius }, material, name) {
    const points = centreline.map((p) => new THREE.Vector3(...p));
    const path = new THREE.CurvePath();
    for (let k = 1; k < points.length; k++) path.add(new THREE.LineCurve3(points[k - 1], points[k]));
    const tube = new THREE.Mesh(new THREE.TubeGeometry(path, 16 * (points.length - 1), radius, 24, false), material);
    tube.name = name;
    const meshes = [tube];
    if (points.length === 3) {
      const ball = new THREE.Mesh(new THREE.SphereGeometry(radius, 24, 16), material);
      ball.position.copy(points[1]);
      ball.name = `${name} corner`;
      meshes.push(ball);
    }
    return meshes;
  }

  /** A fitting's target for the server: tip (mm) and quaternion [w, x, y, z]. */
  static target(object) {
    const q = object.quaternion;
    return { point: object.position.toArray(), quaternion: [q.w, q.x, q.y, q.z] };
  }
}
