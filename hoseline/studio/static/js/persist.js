// What the page keeps across a reload (the browser's localStorage): the camera, the colour map, the selected
// fitting and gizmo mode, the snapping steps.  The hose's state and the undo history live in the server's session,
// which a reloaded page is sent.  The camera is put back only for the same file (its name and the session's revision).

const KEY = 'hoseline-studio-view';

export class Persisted {
  constructor() {
    try { this.kept = JSON.parse(localStorage.getItem(KEY)) || {}; } catch { this.kept = {}; }
    this.timer = null;
  }

  /** Keep `values` (merged into what is kept), written at most every 200 ms. */
  keep(values) {
    Object.assign(this.kept, values);
    clearTimeout(this.timer);
    this.timer = setTimeout(() => {
      try { localStorage.setItem(KEY, JSON.stringify(this.kept)); } catch { /* storage off or full: nothing is kept */ }
    }, 200);
  }

  /** Keep the camera of the view of session `sessionKey`. */
  keepCamera(studioScene, sessionKey) {
    const { camera, orbit } = studioScene;
    this.keep({ camera: { session: sessionKey, position: camera.position.toArray(), target: orbit.target.toArray(), near: camera.near, far: camera.far } });
  }

  /** Put back the camera kept for session `sessionKey`; false when none was kept for it. */
  restoreCamera(studioScene, sessionKey) {
    const kept = this.kept.camera;
    if (!kept || kept.session !== sessionKey) return false;
    const { camera, orbit } = studioScene;
    camera.position.fromArray(kept.position);
    Object.assign(camera, { near: kept.near, far: kept.far });
    orbit.target.fromArray(kept.target);
    studioScene.cameraMoved();
    return true;
  }
}
