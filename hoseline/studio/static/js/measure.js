// The measuring tool: two points picked on what is drawn (the hose, a fitting or clip, an obstacle) and the distance
// between them, shown as a line in the view and as numbers over it.  Switched with M or the toolbar; a third
// pick starts a new measure, Esc leaves the tool.
import * as THREE from 'three';

const fmt = (x) => String(Number(x.toFixed(3)));

export class Measure {
  /** studioScene: the view; targets: the groups that may be picked, by name ({hose, fitting, obstacle}); toolbar:
   * where its button goes; view: the element its readout lies over. */
  constructor(studioScene, targets, toolbar, view) {
    this.studioScene = studioScene;
    this.targets = targets;
    this.active = false;
    this.points = [];
    this.button = Object.assign(document.createElement('button'), { id: 'measure', textContent: 'Measure', title: 'distance between two points picked on the hose, a fitting or an obstacle (M)' });
    toolbar.append(this.button);
    this.button.addEventListener('click', () => this.set(!this.active));
    this.readout = Object.assign(document.createElement('div'), { id: 'measure-readout', hidden: true });
    view.append(this.readout);
    this.group = new THREE.Group();
    this.group.name = 'measure';
    studioScene.scene.add(this.group);
    this.raycaster = new THREE.Raycaster();
    const canvas = studioScene.renderer.domElement;
    let down = null;  // a pick is a press and release without moving (a drag orbits the view)
    canvas.addEventListener('pointerdown', (event) => { down = [event.clientX, event.clientY]; });
    canvas.addEventListener('pointerup', (event) => {
      if (this.active && down && Math.hypot(event.clientX - down[0], event.clientY - down[1]) < 4) this.pick(event);
      down = null;
    });
  }

  /** Switch the tool on or off (off clears the measure). */
  set(active) {
    this.active = active;
    this.button.classList.toggle('active', active);
    if (!active) this.clear();
    this.readout.hidden = !active;
    if (active) this.readout.textContent = 'pick a point on the hose, a fitting or an obstacle';
  }

  clear() {
    this.points = [];
    this.group.traverse((child) => { if (child.geometry) { child.geometry.dispose(); child.material.dispose(); } });
    this.group.clear();
    this.studioScene.requestRender();
  }

  /** The point of the view under a pointer event, on the nearest of the targets: {point, what} or null. */
  hit(event) {
    const rect = event.target.getBoundingClientRect();
    const pointer = new THREE.Vector2(((event.clientX - rect.left) / rect.width) * 2 - 1, -((event.clientY - rect.top) / rect.height) * 2 + 1);
    this.raycaster.setFromCamera(pointer, this.studioScene.camera);
    let best = null;
    for (const [what, group] of Object.entries(this.targets)) {
      const found = this.raycaster.intersectObjects([group], true).find((h) => h.object.isMesh);
      if (found && (!best || found.distance < best.distance)) best = { distance: found.distance, point: found.point, what: `${what} ${found.object.name}`.trim() };
    }
    return best;
  }

  pick(event) {
    const found = this.hit(event);
    if (!found) return;
    if (this.points.length === 2) this.clear();
    this.points.push(found);
    const size = this.studioScene.camera.position.distanceTo(found.point) / 150;
    const marker = new THREE.Mesh(new THREE.SphereGeometry(size, 12, 8), new THREE.MeshBasicMaterial({ color: 0x111111, depthTest: false }));
    marker.position.copy(found.point);
    marker.renderOrder = 10;
    this.group.add(marker);
    if (this.points.length === 2) {
      const [a, b] = this.points;
      const line = new THREE.Line(new THREE.BufferGeometry().setFromPoints([a.point, b.point]),
        new THREE.LineBasicMaterial({ color: 0x111111, depthTest: false }));
      line.renderOrder = 10;
      this.group.add(line);
      const offset = b.point.clone().sub(a.point);
      this.distance = offset.length();
      this.readout.textContent = `${fmt(this.distance)} mm [${offset.toArray().map(fmt).join(', ')}] from ${a.what} to ${b.what}`;
    } else {
      this.readout.textContent = `from ${found.what} at [${found.point.toArray().map(fmt).join(', ')}]: pick the second point`;
    }
    this.studioScene.requestRender();
  }
}
