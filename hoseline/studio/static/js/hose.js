// The hose as a tube round its centreline, coloured per station, with a lay line along the
// section axis d1 that shows the twist.  The buffers are made once per segment count and then
// only overwritten, so a new shape costs a few thousand vertex writes.  Phong shading: in software WebGL (no GPU) a
// frame takes a quarter less than with the physically based material, for much the same look.
import * as THREE from 'three';

const AROUND = 16;  // vertices round the tube

export class HoseView {
  constructor(scene) {
    this.group = new THREE.Group();
    scene.add(this.group);
    this.stations = 0;
  }

  _build(stations) {
    this.group.clear();
    const geometry = new THREE.BufferGeometry();
    const count = stations * AROUND;
    geometry.setAttribute('position', new THREE.BufferAttribute(new Float32Array(3 * count), 3).setUsage(THREE.DynamicDrawUsage));
    geometry.setAttribute('normal', new THREE.BufferAttribute(new Float32Array(3 * count), 3).setUsage(THREE.DynamicDrawUsage));
    geometry.setAttribute('color', new THREE.BufferAttribute(new Float32Array(3 * count), 3).setUsage(THREE.DynamicDrawUsage));
    const index = [];
    for (let i = 0; i + 1 < stations; i++) {
      for (let k = 0; k < AROUND; k++) {
        const a = i * AROUND + k, b = i * AROUND + ((k + 1) % AROUND), c = a + AROUND, d = b + AROUND;
        index.push(a, b, d, a, d, c);
      }
    }
    geometry.setIndex(index);
    this.tube = new THREE.Mesh(geometry, new THREE.MeshPhongMaterial({ vertexColors: true, shininess: 30 }));
    this.tube.name = 'hose';
    this.tube.frustumCulled = false;
    const line = new THREE.BufferGeometry();
    line.setAttribute('position', new THREE.BufferAttribute(new Float32Array(3 * stations), 3).setUsage(THREE.DynamicDrawUsage));
    this.layLine = new THREE.Line(line, new THREE.LineBasicMaterial({ color: 0xffffff }));
    this.layLine.frustumCulled = false;
    this.group.add(this.tube, this.layLine);
    this.stations = stations;
  }

  /** Draw the shape of a state message with per-station colours ([r, g, b] each). */
  update(state, colours) {
    const points = state.centerline, axes = state.lay_line, n = points.length;
    if (n !== this.stations) this._build(n);
    const radius = state.hose.outer_diameter / 2;
    const position = this.tube.geometry.attributes.position.array;
    const normal = this.tube.geometry.attributes.normal.array;
    const colour = this.tube.geometry.attributes.color.array;
    const line = this.layLine.geometry.attributes.position.array;
    for (let i = 0; i < n; i++) {
      const p = points[i], d1 = axes[i];
      const before = points[Math.max(i - 1, 0)], after = points[Math.min(i + 1, n - 1)];
      let tx = after[0] - before[0], ty = after[1] - before[1], tz = after[2] - before[2];
      const length = Math.hypot(tx, ty, tz) || 1;
      tx /= length; ty /= length; tz /= length;
      const d2 = [ty * d1[2] - tz * d1[1], tz * d1[0] - tx * d1[2], tx * d1[1] - ty * d1[0]];
      const c = colours[i];
      for (let k = 0; k < AROUND; k++) {
        const angle = (2 * Math.PI * k) / AROUND, cos = Math.cos(angle), sin = Math.sin(angle);
        const j = 3 * (i * AROUND + k);
        for (let m = 0; m < 3; m++) {
          const out = cos * d1[m] + sin * d2[m];
          normal[j + m] = out;
          position[j + m] = p[m] + radius * out;
          colour[j + m] = c[m];
        }
      }
      for (let m = 0; m < 3; m++) line[3 * i + m] = p[m] + 1.04 * radius * d1[m];
    }
    for (const name of ['position', 'normal', 'color']) this.tube.geometry.attributes[name].needsUpdate = true;
    this.layLine.geometry.attributes.position.needsUpdate = true;
  }

  /** Bounds of the hose (THREE.Box3). */
  bounds() {
    this.tube.geometry.computeBoundingBox();
    return this.tube.geometry.boundingBox.clone();
  }
}
