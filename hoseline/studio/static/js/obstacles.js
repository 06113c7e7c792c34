// Obstacles: meshes fetched once per session (binary: counts, float32 vertices, uint32 triangles),
// placed by the pose of the body they move with.
import * as THREE from 'three';

const NEAR = 0.1;  // of the hose's diagonal: the reach round the hose within which obstacles are framed with it

export class ObstacleView {
  constructor(scene) {
    this.group = new THREE.Group();
    scene.add(this.group);
    this.meshes = [];
  }

  /** Load the obstacles of a session message; resolves when all are shown. */
  async load(list) {
    const meshes = await Promise.all(list.map(async (item) => {
      const response = await fetch(`/obstacle/${item.id}`);
      if (!response.ok) throw new Error(`obstacle ${item.name}: ${response.status}`);
      const data = await response.arrayBuffer();
      const [vertices, faces] = new Uint32Array(data, 0, 2);
      const geometry = new THREE.BufferGeometry();
      geometry.setAttribute('position', new THREE.BufferAttribute(new Float32Array(data, 8, 3 * vertices), 3));
      geometry.setIndex(new THREE.BufferAttribute(new Uint32Array(data, 8 + 12 * vertices, 3 * faces), 1));
      geometry.computeVertexNormals();
      const material = new THREE.MeshLambertMaterial({ color: 0xa0a8b0, transparent: true, opacity: 0.6 });
      const mesh = new THREE.Mesh(geometry, material);
      mesh.name = item.name;
      mesh.matrixAutoUpdate = false;
      return mesh;
    }));
    this.group.clear();
    this.meshes = meshes;
    for (const mesh of meshes) this.group.add(mesh);
  }

  /** Move the obstacles to the poses of a state message (4x4 matrices, row by row). */
  place(poses) {
    poses.forEach((rows, k) => {
      if (this.meshes[k]) this.meshes[k].matrix.set(...rows);
    });
  }

  /** A box (THREE.Box3, mm) round `box` and the parts of the obstacles near it: within NEAR of its diagonal.  The
   * view is fitted to it, so that a large obstacle (a contact plane is drawn four hose lengths wide) does not make
   * the hose small. */
  boundsNear(box) {
    const near = box.clone().expandByScalar(NEAR * box.getSize(new THREE.Vector3()).length());
    const framed = box.clone();
    for (const mesh of this.meshes) {
      const part = new THREE.Box3().setFromObject(mesh).intersect(near);
      if (!part.isEmpty()) framed.union(part);
    }
    return framed;
  }
}
