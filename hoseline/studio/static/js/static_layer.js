// A group that does not change during a drag (the obstacles) drawn into a layer kept between frames: colour
// (premultiplied) and depth, drawn again only when the camera, the canvas or the group's objects move.  Each frame
// draws the rest of the scene and lays the layer over it, each pixel in front of what the frame has there or
// hidden behind it (its depth written from the layer's), as if the group had been drawn with the scene.  Why:
// without a GPU (SwiftShader draws WebGL on the CPU) a mesh obstacle of 100 000 triangles costs some 30 ms a
// frame, the laying over a fraction of it.
import * as THREE from 'three';

const VERTEX = 'varying vec2 vUv;\nvoid main() { vUv = uv; gl_Position = vec4(position.xy, 0.0, 1.0); }';
// the layer holds linear colours, premultiplied; the canvas takes the output colour space's (linearToOutputTexel)
const FRAGMENT = `uniform sampler2D colour;
uniform sampler2D depth;
varying vec2 vUv;
void main() {
  vec4 texel = texture2D(colour, vUv);
  gl_FragDepth = texture2D(depth, vUv).x;
  vec3 straight = texel.a > 0.0 ? texel.rgb / texel.a : vec3(0.0);
  gl_FragColor = vec4(linearToOutputTexel(vec4(straight, 1.0)).rgb * texel.a, texel.a);
}`;

export class StaticLayer {
  /** group: the objects drawn into the layer (THREE.Group); they must not change between frames unseen: a
   * change of their matrices or count is seen, anything else needs forget(). */
  constructor(group) {
    this.group = group;
    this.layers = new Map();  // 'width x height' of the drawing buffer -> {target, key, rectangle}: the last two sizes
    this.layer = null;  // the one drawn last
    this.quad = new THREE.Mesh(new THREE.PlaneGeometry(2, 2), new THREE.ShaderMaterial({
      vertexShader: VERTEX, fragmentShader: FRAGMENT, uniforms: { colour: { value: null }, depth: { value: null } },
      transparent: true, depthTest: true, depthWrite: false, blending: THREE.CustomBlending,
      blendSrc: THREE.OneFactor, blendDst: THREE.OneMinusSrcAlphaFactor,
      blendSrcAlpha: THREE.OneFactor, blendDstAlpha: THREE.OneMinusSrcAlphaFactor,
    }));
    this.quad.frustumCulled = false;
    this.quadScene = new THREE.Scene().add(this.quad);
    this.quadCamera = new THREE.OrthographicCamera();
  }

  /** Draw the layer afresh at the next frame. */
  forget() { for (const layer of this.layers.values()) layer.key = null; }

  /** The rectangle of the canvas the group covers in the layer of the size drawn last (see onScreen). */
  get rectangle() { return this.layer?.rectangle; }

  /** Draw `scene` as seen by `camera`, the group from the layer of the drawing buffer's size (drawn into it first if
   * stale).  A layer is kept for each of the last two sizes: the view drawn at a lower resolution during a drag
   * (scene.js) finds its full-resolution layer still good after it. */
  render(renderer, scene, camera) {
    if (!this.group.children.length) { renderer.render(scene, camera); return; }
    const size = renderer.getDrawingBufferSize(new THREE.Vector2()), sizeKey = `${size.x}x${size.y}`;
    let layer = this.layers.get(sizeKey);
    if (!layer) {
      const depthTexture = new THREE.DepthTexture(size.x, size.y);
      layer = { target: new THREE.WebGLRenderTarget(size.x, size.y, { depthTexture }), key: null, rectangle: null };
      this.layers.set(sizeKey, layer);
      for (const [other, { target }] of [...this.layers].slice(0, -2)) { target.dispose(); this.layers.delete(other); }
    }
    this.layer = layer;
    this.quad.material.uniforms.colour.value = layer.target.texture;
    this.quad.material.uniforms.depth.value = layer.target.depthTexture;
    scene.updateMatrixWorld();
    camera.updateMatrixWorld();
    const key = [...camera.matrixWorld.elements, ...camera.projectionMatrix.elements,
      ...this.group.children.flatMap((child) => child.matrixWorld.elements)].join(',');
    if (key !== layer.key) {
      this.drawLayer(renderer, scene, camera, layer.target);
      layer.key = key;
      layer.rectangle = onScreen(new THREE.Box3().setFromObject(this.group), camera, renderer);
    }
    this.group.visible = false;
    renderer.render(scene, camera);
    this.group.visible = true;
    const autoClear = renderer.autoClear;
    renderer.autoClear = false;
    renderer.setScissor(...layer.rectangle);  // the layer's pixels only: a full-canvas pass costs the CPU too
    renderer.setScissorTest(true);
    renderer.render(this.quadScene, this.quadCamera);
    renderer.setScissorTest(false);
    renderer.autoClear = autoClear;
  }

  /** The group alone (with the scene's lights) into `target`, on a clear of nothing (colour 0, alpha 0). */
  drawLayer(renderer, scene, camera, target) {
    const hidden = scene.children.filter((child) => child !== this.group && !child.isLight && child.visible);
    hidden.forEach((child) => { child.visible = false; });
    const background = renderer.getClearColor(new THREE.Color()), alpha = renderer.getClearAlpha();
    renderer.setRenderTarget(target);
    renderer.setClearColor(0x000000, 0);
    renderer.clear();
    renderer.render(scene, camera);
    renderer.setRenderTarget(null);
    renderer.setClearColor(background, alpha);
    hidden.forEach((child) => { child.visible = true; });
  }
}

/** The rectangle of the canvas (x, y, width, height in CSS pixels, from the bottom left) that `box` (THREE.Box3) covers
 * as seen by `camera`; the whole canvas when part of it lies behind the camera. */
function onScreen(box, camera, renderer) {
  const size = renderer.getSize(new THREE.Vector2());
  const corners = [0, 1, 2, 3, 4, 5, 6, 7].map((k) => new THREE.Vector3(
    k & 1 ? box.max.x : box.min.x, k & 2 ? box.max.y : box.min.y, k & 4 ? box.max.z : box.min.z));
  const view = corners.map((corner) => corner.clone().applyMatrix4(camera.matrixWorldInverse));
  if (box.isEmpty() || view.some((point) => point.z > -camera.near)) return [0, 0, size.x, size.y];
  const ndc = corners.map((corner) => corner.project(camera));
  const clamp = (v) => Math.min(Math.max(v, -1), 1);
  const [left, right] = [Math.min(...ndc.map((p) => clamp(p.x))), Math.max(...ndc.map((p) => clamp(p.x)))];
  const [bottom, top] = [Math.min(...ndc.map((p) => clamp(p.y))), Math.max(...ndc.map((p) => clamp(p.y)))];
  const x = Math.floor(((left + 1) / 2) * size.x), y = Math.floor(((bottom + 1) / 2) * size.y);
  return [x, y, Math.ceil(((right + 1) / 2) * size.x) - x + 1, Math.ceil(((top + 1) / 2) * size.y) - y + 1];
}
