// Focus: turn the view onto a point (the selected fitting or clip), keeping the direction it is looked at from,
// close enough to see it and the hose near it.
import * as THREE from 'three';

/** Look at `point` (THREE.Vector3, mm) from the current direction so that a sphere of `radius` mm fills the view. */
export function focusOn(studioScene, point, radius) {
  const { camera, orbit } = studioScene;
  const direction = camera.position.clone().sub(orbit.target).normalize();
  const distance = radius / Math.sin(THREE.MathUtils.degToRad(camera.fov / 2)) * Math.max(1, 1 / camera.aspect);
  camera.position.copy(point).addScaledVector(direction, distance);
  camera.near = distance / 100;
  camera.far = distance * 100;
  orbit.target.copy(point);
  studioScene.cameraMoved();
}
