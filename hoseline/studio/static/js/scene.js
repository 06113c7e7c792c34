// The 3D view: renderer, camera (z up, as the problem files' gravity), orbit/pan/zoom, a ground
// grid and axes, view presets.  It draws on demand (after a change), not in a loop: requestRender() marks the
// view dirty and one drawing draws it, however many changes came before it (a drag's events, the states
// answering them, the orbit's moves).  Without a GPU a drawing takes the CPU for 10 ms or more, and drawn just
// after a drag's target was sent it held up the answer.  So the view is drawn at once (when the caller's task
// is done) while no answer from the server is awaited nor another target expected within a frame (streaming: a
// drag at the rate of the frames), and the last drawing is MIN_INTERVAL_MS old; else at the next animation frame,
// and a frame due while an answer is expected soon (awaitedUntil) waits for it, at most until then, and is drawn
// as soon as it comes: one drawing shows the answer, taken in at once.  Drawn in software, a drag is drawn at half
// the resolution until it pauses (dragged()): each frame's commit holds the main thread the longer the larger the
// canvas, and held up pointer moves and answers.
import * as THREE from 'three';
import { OrbitControls } from 'three/addons/controls/OrbitControls.js';
import { StaticLayer } from './static_layer.js';

const MIN_INTERVAL_MS = 8;  // between drawings made at once, outside the animation frames (half a frame at 60 Hz)
// Drawn in software (no GPU), a drag is drawn at this share of the full resolution (in each direction) until it
// pauses for PAUSE_MS or ends, then at full resolution again: the rasteriser's time and each frame's commit go
// with the pixels (with the strut, a commit held the main thread 9 ms at full resolution, 3.6-4.3 at half), and
// the rasteriser shares the CPU with the server's solver.
const DRAG_RESOLUTION = 0.5;
const PAUSE_MS = 250;

const PRESETS = {
  iso: new THREE.Vector3(1, -1, 0.8),
  top: new THREE.Vector3(0, -1e-3, 1),
  front: new THREE.Vector3(0, -1, 0),
  side: new THREE.Vector3(1, 0, 0),
};

/** Whether WebGL here runs on the CPU (no GPU driver), from the unmasked renderer name. */
function softwareRendering() {
  const gl = document.createElement('canvas').getContext('webgl2');
  const info = gl && gl.getExtension('WEBGL_debug_renderer_info');
  const name = info ? String(gl.getParameter(info.UNMASKED_RENDERER_WEBGL)) : '';
  gl?.getExtension('WEBGL_lose_context')?.loseContext();
  return /swiftshader|llvmpipe|software/i.test(name);
}

export class StudioScene {
  constructor(container) {
    this.container = container;
    // multisampling costs a software renderer (no GPU: SwiftShader, llvmpipe) more than twice the frame time
    this.software = softwareRendering();
    this.renderer = new THREE.WebGLRenderer({ antialias: !this.software });
    this.fullPixelRatio = Math.min(window.devicePixelRatio, 2);
    this.renderer.setPixelRatio(this.fullPixelRatio);
    this.paused = null;  // the timer that draws the full resolution again once a drag pauses
    this.renderer.setClearColor(0xf3f5f7);
    container.prepend(this.renderer.domElement);
    this.scene = new THREE.Scene();
    this.camera = new THREE.PerspectiveCamera(35, 1, 1, 1e5);
    this.camera.up.set(0, 0, 1);
    this.scene.add(new THREE.HemisphereLight(0xffffff, 0x8090a0, 2.0));
    const sun = new THREE.DirectionalLight(0xffffff, 1.6);
    sun.position.set(1, -2, 3);
    this.scene.add(sun);
    this.orbit = new OrbitControls(this.camera, this.renderer.domElement);
    // the view turned, panned or zoomed by a pointer drag (not by a preset, a focus or the wheel: state none, -1)
    this.orbit.addEventListener('change', () => { if (this.orbit.state !== -1) this.dragged(); this.requestRender(); });
    this.ground = new THREE.Group();
    this.scene.add(this.ground);
    this.drawCount = 0;
    this.dirty = false;
    this.drawnCallbacks = [];  // called with performance.now() once the next frame is drawn
    this.later = null;  // the timer of requestRenderAfter
    this.held = null;  // the timer of a frame held for an awaited answer
    this.drawnAt = -Infinity;  // performance.now() of the last drawing
    this.awaitedUntil = () => null;  // performance.now() until which a frame waits for an answer (null: none awaited)
    this.streaming = () => false;  // whether targets go to the server at about the rate of the frames
    new ResizeObserver(() => this.resize()).observe(container);
    this.resize();
  }

  resize() {
    const { clientWidth: width, clientHeight: height } = this.container;
    if (width === 0 || height === 0) return;
    this.renderer.setSize(width, height, false);
    this.camera.aspect = width / height;
    this.camera.updateProjectionMatrix();
    this.requestRender();
  }

  /** A drag began or moved something (the gizmo, or the view by the pointer): drawn in software, the view is drawn
   * at DRAG_RESOLUTION until the drags pause for PAUSE_MS. */
  dragged() {
    if (!this.software) return;
    clearTimeout(this.paused);
    this.paused = setTimeout(() => { this.paused = null; this.setPixelRatio(this.fullPixelRatio); }, PAUSE_MS);
    this.setPixelRatio(DRAG_RESOLUTION * this.fullPixelRatio);
  }

  /** Draw at `ratio` drawing-buffer pixels per CSS pixel, drawn at once where it changes (a canvas resized is
   * cleared, and would be shown blank until the next drawing). */
  setPixelRatio(ratio) {
    if (this.renderer.getPixelRatio() === ratio) return;
    this.renderer.setPixelRatio(ratio);
    this.render();
  }

  /** Draw once, however often asked before it: at once (when the caller's task is done) where a frame was held
   * for an answer, or where none is awaited nor streaming and the last drawing is MIN_INTERVAL_MS old; else at the
   * next animation frame.  then(performance.now()) is called when it has been drawn. */
  requestRender(then) {
    if (then) this.drawnCallbacks.push(then);
    clearTimeout(this.later);
    this.later = null;
    if (this.held !== null) {
      clearTimeout(this.held);
      this.held = null;
      this.renderSoon();
      return;
    }
    if (this.dirty) return;
    this.dirty = true;
    if (this.awaitedUntil() === null && !this.streaming() && performance.now() - this.drawnAt >= MIN_INTERVAL_MS) {
      this.renderSoon();
      return;
    }
    requestAnimationFrame(() => this.frame());
  }

  /** Draw when the caller's task is done, unless drawn before then. */
  renderSoon() {
    queueMicrotask(() => { if (this.dirty) this.render(); });
  }

  /** An animation frame: draw, or hold the drawing until the answer awaited comes (requestRender) or is late. */
  frame() {
    if (!this.dirty || this.held !== null) return;  // drawn at once meanwhile, or held already
    const until = this.awaitedUntil(), now = performance.now();
    if (until === null || until <= now) { this.render(); return; }
    this.held = setTimeout(() => { this.held = null; this.render(); }, until - now);
  }

  /** Draw in `ms` milliseconds, unless a frame is asked for before then (which draws this change too). */
  requestRenderAfter(ms) {
    if (this.later === null && !this.dirty) this.later = setTimeout(() => this.requestRender(), ms);
  }

  /** Draw now, and call the callbacks waiting for a frame. */
  render() {
    this.dirty = false;
    if (this.layer) this.layer.render(this.renderer, this.scene, this.camera);
    else this.renderer.render(this.scene, this.camera);
    this.drawCount += 1;
    const drawnAt = this.drawnAt = performance.now(), callbacks = this.drawnCallbacks;
    this.drawnCallbacks = [];
    for (const then of callbacks) then(drawnAt);
  }

  /** Draw `group` (of this scene; objects that stay put during a drag: the obstacles) into a layer kept between
   * frames (static_layer.js); its objects are seen to move by their matrices; forgetLayer() after any other change. */
  keepDrawn(group) {
    this.layer = new StaticLayer(group);
  }

  forgetLayer() {
    this.layer?.forget();
    this.requestRender();
  }

  /** A ground grid below `box` (THREE.Box3, mm) and axes at the origin, sized to it. */
  setGround(box) {
    this.ground.clear();
    const size = box.getSize(new THREE.Vector3());
    const extent = Math.max(size.x, size.y, size.z, 1);
    const step = 10 ** Math.floor(Math.log10(extent / 5));
    const span = Math.ceil((2 * extent) / step) * step;
    const grid = new THREE.GridHelper(span, Math.round(span / step), 0x9aa7b5, 0xd0d7de);
    grid.rotation.x = Math.PI / 2;  // GridHelper lies in xz; the ground is the xy plane
    const centre = box.getCenter(new THREE.Vector3());
    grid.position.set(Math.round(centre.x / step) * step, Math.round(centre.y / step) * step, box.min.z - 0.1 * extent);
    this.ground.add(grid);
    const axes = new THREE.AxesHelper(0.25 * extent);
    this.ground.add(axes);
    this.bounds = box.clone();
  }

  /** Look at the bounds from a preset direction (iso, top, front, side) or keep the direction (fit). */
  view(name) {
    if (!this.bounds) return;
    const centre = this.bounds.getCenter(new THREE.Vector3());
    const radius = Math.max(this.bounds.getSize(new THREE.Vector3()).length() / 2, 1);
    const direction = name in PRESETS ? PRESETS[name].clone().normalize()
      : this.camera.position.clone().sub(this.orbit.target).normalize();
    const distance = radius / Math.sin(THREE.MathUtils.degToRad(this.camera.fov / 2)) * Math.max(1, 1 / this.camera.aspect);
    this.camera.position.copy(centre).addScaledVector(direction, distance);
    this.camera.near = distance / 100;
    this.camera.far = distance * 100;
    this.orbit.target.copy(centre);
    this.cameraMoved();
  }

  /** The camera was put somewhere by the page (a preset view, a focus, the view kept over a reload): its matrices
   * made current at once, not at the next drawing, so that a pick (a click's raycast) before that drawing sees the
   * view as it will be drawn, then drawn. */
  cameraMoved() {
    this.camera.updateProjectionMatrix();
    this.orbit.update();
    this.camera.updateMatrixWorld();
    this.requestRender();
  }
}
