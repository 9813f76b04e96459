// The 3D view, apart from every panel (as gzweb keeps gz3d apart from gzgui):
// it draws the scene the simulator sends and the poses it streams, and turns
// the mouse into selections and drags. It keeps no world of its own: a drag
// moves the model here only until the simulator's next pose for it.
//
// Events (EventTarget): select {name|null}; dragstart {name}; drag {name, pose};
// dragend {name, pose}; scaled {name, scale: [sx, sy, sz]} (a drag of the Scale tool's handles);
// modelmenu {name, x, y} (a right click on a model); follow {name|null}. A pose is [x, y, z, roll, pitch, yaw], fixed axes as SDF.

import * as THREE from 'three';
import {OrbitControls} from 'three/addons/controls/OrbitControls.js';
import {TransformControls} from 'three/addons/controls/TransformControls.js';
import {buildCollisions, buildModel} from './shapes.js';
import {addLights, bakeStatic, floorColor} from './lighting.js';

THREE.Object3D.DEFAULT_UP.set(0, 0, 1);

export function setPose(object, pose) {
  object.position.set(pose[0], pose[1], pose[2]);
  object.rotation.set(pose[3], pose[4], pose[5], 'ZYX');
}

function samePose(object, pose) {
  const [x, y, z, roll, pitch, yaw] = pose;
  const at = object.position;
  const turned = object.rotation;
  return at.x === x && at.y === y && at.z === z && turned.x === roll && turned.y === pitch
    && turned.z === yaw;
}

export function poseOf(object) {
  const euler = new THREE.Euler().setFromQuaternion(object.quaternion, 'ZYX');
  return [object.position.x, object.position.y, object.position.z, euler.x, euler.y, euler.z];
}

// A click moves the pointer less than this (pixels); more is an orbit or a drag.
const CLICK_SLOP = 4;
// A browser drawing on the CPU draws a quarter of the pixels while something moves, and
// one sharp frame once nothing has moved for REST_MS.
const SOFTWARE_MOTION_PIXEL_RATIO = 0.5;
const REST_MS = 400;
const MAX_PIXEL_RATIO = 2;

// Whether WebGL runs on the CPU (SwiftShader, llvmpipe): no GPU to draw for us.
function drawsOnCpu(renderer) {
  const gl = renderer.getContext();
  const info = gl.getExtension('WEBGL_debug_renderer_info');
  const name = String(gl.getParameter(info ? info.UNMASKED_RENDERER_WEBGL : gl.RENDERER));
  return /swiftshader|llvmpipe|softpipe|software/i.test(name);
}

// Gazebo's grey grid: 20 by 20 squares of 1 m around the origin (GRID_HALF each way). Each line
// is drawn in 1 m pieces: a software renderer drops a whole line when one of its ends lies
// behind the camera, which left no grid near the origin.
const GRID_HALF = 10;

function floorGrid() {
  const points = [];
  for (let line = -GRID_HALF; line <= GRID_HALF; line += 1) {
    for (let along = -GRID_HALF; along < GRID_HALF; along += 1) {
      points.push(line, along, 0, line, along + 1, 0, along, line, 0, along + 1, line, 0);
    }
  }
  const geometry = new THREE.BufferGeometry();
  geometry.setAttribute('position', new THREE.Float32BufferAttribute(points, 3));
  const grid = new THREE.LineSegments(geometry, new THREE.LineBasicMaterial(
    {color: 0xcfcfcf, depthTest: false, depthWrite: false}));
  grid.name = 'grid';
  return grid;
}

export class SceneView extends EventTarget {
  constructor(canvas) {
    super();
    this.canvas = canvas;
    // No antialiasing: a browser without a GPU draws every frame on the CPU, the
    // simulator's CPU when both run on one machine.
    // Transparent where nothing is drawn: the sky behind it is the canvas's CSS background
    // (setSky), which costs a CPU-drawing browser nothing per frame.
    this.renderer = new THREE.WebGLRenderer({canvas, antialias: false, alpha: true,
                                             powerPreference: 'low-power'});
    this.renderer.setClearColor(0x000000, 0);
    // Checking each shader waits for the GPU process; three.js's own shaders compile.
    this.renderer.debug.checkShaderErrors = false;
    this.restPixelRatio = Math.min(window.devicePixelRatio || 1, MAX_PIXEL_RATIO);
    this.motionPixelRatio = drawsOnCpu(this.renderer) ? SOFTWARE_MOTION_PIXEL_RATIO
                                                      : this.restPixelRatio;
    this.renderer.setPixelRatio(this.restPixelRatio);
    this.scene = new THREE.Scene();
    this.camera = new THREE.PerspectiveCamera(50, 1, 0.05, 500);
    this.camera.position.set(-6, -6, 5);
    this.orbit = new OrbitControls(this.camera, canvas);
    // Gazebo's mouse (its OrbitViewController): a left drag pans, a middle drag orbits (so does
    // Shift with a left drag: the controls swap pan and orbit while Shift is held), and a right
    // drag or the wheel zooms.
    this.orbit.mouseButtons = {LEFT: THREE.MOUSE.PAN, MIDDLE: THREE.MOUSE.ROTATE,
                               RIGHT: THREE.MOUSE.DOLLY};
    this.orbit.addEventListener('change', () => this.requestRender(true));
    this.transform = new TransformControls(this.camera, canvas);
    this.transform.setSize(0.9);
    this.transform.addEventListener('change', () => this.requestRender(true));
    this.transform.addEventListener('dragging-changed', (event) => this.onDragging(event.value));
    this.transform.addEventListener('objectChange', () => this.onObjectChange());
    this.scene.add(this.transform.getHelper());
    this.addFloor();
    this.models = new Map();          // name -> {group, links: Map(name -> Object3D), description}
    this.staticBatch = null;          // the static models, drawn as one mesh (lighting.js)
    this.batchStale = false;
    this.selected = null;
    this.selectionBox = null;
    this.mode = 'select';
    this.dragged = null;
    this.scanLines = null;
    this.showCones = false;
    this.frameRequested = false;
    this.moving = false;              // something moved since the last frame
    this.restTimer = null;
    this.posesChanged = false;
    this.poseFrames = 0;              // rendered frames that showed a new pose (for the benchmark)
    this.pointerDown = null;
    this.looks = new Map();           // model -> {transparent, wireframe, collisions}: the model menu's View
    this.followed = null;             // the model the camera follows (the model menu's Follow)
    canvas.addEventListener('pointerdown', (event) => this.onPointerDown(event));
    canvas.addEventListener('pointerup', (event) => this.onPointerUp(event));
    new ResizeObserver(() => this.resize()).observe(canvas);
    this.resize();
  }

  addFloor() {
    addLights(this.scene);
    // The floor first, then the grid on it without a depth test (a depth buffer cannot tell
    // two planes a millimetre apart), then the models.
    this.ground = new THREE.Mesh(new THREE.PlaneGeometry(200, 200), new THREE.MeshBasicMaterial());
    this.setFloorColor(new THREE.Color(0x777777));
    this.ground.position.z = -0.001;
    this.ground.renderOrder = -2;
    this.scene.add(this.ground);
    const grid = floorGrid();
    grid.renderOrder = -1;
    this.scene.add(grid);
  }

  // Gazebo's sky: the world's background colour at the horizon, turning blue-grey overhead,
  // as a gradient down the view. A textured background would be drawn again with every
  // frame, which halved the frame rate of a browser that draws on the CPU.
  setSky(color) {
    const overhead = color.clone().lerp(new THREE.Color(0.36, 0.47, 0.62), 0.7);
    this.canvas.style.background = 'linear-gradient(#' + overhead.getHexString() + ', #'
                                   + color.getHexString() + ')';
  }

  setFloorColor(color) {
    this.ground.material.color.copy(floorColor(color));
  }

  // A frame is drawn only when something changed, at most one per display frame; moving
  // says it was motion (poses, the camera), which a CPU-drawing browser draws with fewer pixels.
  requestRender(moving = false) {
    if (moving) this.moving = true;
    if (this.frameRequested) return;
    this.frameRequested = true;
    requestAnimationFrame(() => {
      this.frameRequested = false;
      this.render();
    });
  }

  resize() {
    const width = this.canvas.clientWidth || 1;
    const height = this.canvas.clientHeight || 1;
    this.renderer.setSize(width, height, false);
    this.camera.aspect = width / height;
    this.camera.updateProjectionMatrix();
    this.requestRender();
  }

  setPixelRatio(ratio) {
    if (ratio === this.renderer.getPixelRatio()) return;
    this.renderer.setPixelRatio(ratio);
    this.renderer.setSize(this.canvas.clientWidth || 1, this.canvas.clientHeight || 1, false);
  }

  render() {
    if (this.moving) {
      this.moving = false;
      this.setPixelRatio(this.motionPixelRatio);
      clearTimeout(this.restTimer);
      this.restTimer = setTimeout(() => {
        this.setPixelRatio(this.restPixelRatio);
        this.requestRender();
      }, REST_MS);
    }
    if (this.batchStale) this.batchStatic();
    if (this.selectionBox) this.fitSelectionBox();
    this.renderer.render(this.scene, this.camera);
    if (this.posesChanged) {
      this.posesChanged = false;
      this.poseFrames += 1;
    }
  }

  // The static models as one baked mesh; their own meshes stay, hidden, for picking.
  // A static model being dragged is left out and drawn by its own meshes, so that it
  // follows the handle.
  batchStatic() {
    this.batchStale = false;
    if (this.staticBatch) {
      this.scene.remove(this.staticBatch);
      this.staticBatch.geometry.dispose();
    }
    const statics = [...this.models.entries()].filter(([, model]) => model.description.static);
    const ownMeshes = (name) => name === this.dragged || this.looks.has(name);
    const baked = statics.filter(([name]) => !ownMeshes(name)).map(([, model]) => model.group);
    this.staticBatch = bakeStatic(baked);
    for (const [name, model] of statics) {
      const own = ownMeshes(name);
      model.group.traverse((object) => {
        if (object.isMesh && !object.material.transparent) object.visible = own;
      });
    }
    if (this.staticBatch) this.scene.add(this.staticBatch);
  }

  // -- what the simulator sends -------------------------------------------------------
  setScene(description) {
    const selected = this.selected;
    this.select(null);
    for (const model of this.models.values()) this.scene.remove(model.group);
    this.models.clear();
    this.setSky(new THREE.Color(...description.sky));
    this.setFloorColor(new THREE.Color(...description.floor));
    for (const model of description.models) {
      const built = buildModel(model);
      for (const cone of built.cones) cone.visible = this.showCones;
      this.models.set(model.name, built);
      this.scene.add(built.group);
    }
    for (const name of [...this.looks.keys()]) {
      if (this.models.has(name)) this.applyLook(name);
      else this.looks.delete(name);
    }
    if (this.followed && !this.models.has(this.followed)) this.follow(null);
    this.batchStale = true;
    if (selected && this.models.has(selected)) this.select(selected);
    this.requestRender();
  }

  applyPoses(models, links) {
    const followed = this.followed && this.models.get(this.followed);
    const before = followed ? followed.group.position.clone() : null;
    for (const [name, pose] of Object.entries(models || {})) {
      const model = this.models.get(name);
      if (!model || name === this.dragged) continue;
      // Static models are drawn where the scene put them; one that moved anyway is drawn anew.
      if (model.description.static && !samePose(model.group, pose)) this.batchStale = true;
      setPose(model.group, pose);
    }
    for (const [name, linkPoses] of Object.entries(links || {})) {
      const model = this.models.get(name);
      if (!model) continue;
      for (const [link, pose] of Object.entries(linkPoses)) {
        const object = model.links.get(link);
        if (object) setPose(object, pose);
      }
    }
    if (followed) {
      // The camera keeps its place relative to the model, as Gazebo's camera tracks it.
      const moved = followed.group.position.clone().sub(before);
      this.camera.position.add(moved);
      this.orbit.target.add(moved);
      this.orbit.update();
    }
    this.posesChanged = true;
    this.requestRender(true);
  }

  setScans(scans) {
    if (this.scanLines) {
      this.scene.remove(this.scanLines);
      this.scanLines.geometry.dispose();
      this.scanLines = null;
    }
    if (!scans) return this.requestRender();
    const points = [];
    for (const scan of scans) {
      const [x, y, z, yaw] = scan.origin;
      const count = scan.ranges.length;
      const step = count > 1 ? (scan.max_angle - scan.min_angle) / (count - 1) : 0;
      scan.ranges.forEach((range, index) => {
        if (range === null) return;
        const angle = yaw + scan.min_angle + index * step;
        points.push(x, y, z, x + range * Math.cos(angle), y + range * Math.sin(angle), z);
      });
    }
    const geometry = new THREE.BufferGeometry();
    geometry.setAttribute('position', new THREE.Float32BufferAttribute(points, 3));
    this.scanLines = new THREE.LineSegments(geometry, new THREE.LineBasicMaterial(
      {color: 0x3399ff, transparent: true, opacity: 0.45}));
    this.scanLines.name = 'lidar rays';
    this.scene.add(this.scanLines);
    this.requestRender();
  }

  setConesVisible(visible) {
    this.showCones = visible;
    for (const model of this.models.values()) {
      for (const cone of model.cones) cone.visible = visible;
    }
    this.requestRender();
  }

  // -- selection and tools --------------------------------------------------------------
  select(name) {
    if (name !== null && !this.models.has(name)) name = null;
    if (this.selectionBox) {
      this.scene.remove(this.selectionBox);
      this.selectionBox = null;
    }
    this.selected = name;
    if (name !== null) {
      this.selectionBox = new THREE.Box3Helper(new THREE.Box3(), 0xf39c12);
      this.fitSelectionBox();
      this.scene.add(this.selectionBox);
    }
    this.attachTransform();
    this.dispatchEvent(new CustomEvent('select', {detail: {name}}));
    this.requestRender();
  }

  // Around the selected model's shapes (not its cameras' fields of view).
  fitSelectionBox() {
    const box = this.selectionBox.box.makeEmpty();
    this.models.get(this.selected).group.traverse((object) => {
      if (object.isMesh) box.expandByObject(object);
    });
  }

  setMode(mode) {
    this.mode = mode;
    this.attachTransform();
    this.requestRender();
  }

  attachTransform() {
    const model = this.selected && this.models.get(this.selected);
    // Every model is moved by hand, static ones too, as in Gazebo.
    if (this.mode === 'select' || !model) {
      this.transform.detach();
      return;
    }
    // Gazebo's Scale tool scales simple shapes only (a box, a cylinder, a sphere).
    if (this.mode === 'scale' && !model.description.simple_shape) {
      this.transform.detach();
      return;
    }
    this.transform.setMode(this.mode);
    // flatsim moves models in the plane and turns them about z: the other handles would lie.
    const translating = this.mode === 'translate';
    const scaling = this.mode === 'scale';
    this.transform.showX = translating || scaling;
    this.transform.showY = translating || scaling;
    this.transform.showZ = !translating;
    this.transform.attach(model.group);
  }

  cancelDrag() {
    this.transform.detach();
    this.dragged = null;
  }

  onDragging(dragging) {
    this.orbit.enabled = !dragging;
    const name = this.transform.object ? this.transform.object.userData.name : this.dragged;
    if (dragging && name) {
      this.dragged = name;
      if (this.models.get(name)?.description.static) this.batchStale = true;
      if (this.mode !== 'scale') this.dispatchEvent(new CustomEvent('dragstart', {detail: {name}}));
    } else if (!dragging && this.dragged) {
      const model = this.models.get(this.dragged);
      if (model?.description.static) this.batchStale = true;
      const pose = model ? poseOf(model.group) : null;
      const name = this.dragged;
      this.dragged = null;
      if (this.mode === 'scale') {
        // Drawn so until the simulator's scene shows the model with its new sizes.
        const scale = model ? model.group.scale.toArray() : [1, 1, 1];
        this.dispatchEvent(new CustomEvent('scaled', {detail: {name, scale}}));
      } else {
        this.dispatchEvent(new CustomEvent('dragend', {detail: {name, pose}}));
      }
      this.attachTransform();
    }
  }

  // A scale drag that the simulator refused: drawn at its own size again.
  unscale(name) {
    const model = this.models.get(name);
    if (!model) return;
    model.group.scale.set(1, 1, 1);
    if (model.description.static) this.batchStale = true;
    this.requestRender();
  }

  onObjectChange() {
    if (!this.dragged || this.mode === 'scale') return;
    const model = this.models.get(this.dragged);
    this.dispatchEvent(new CustomEvent('drag', {detail: {name: this.dragged, pose: poseOf(model.group)}}));
  }

  onPointerDown(event) {
    this.canvas.focus();
    // A press on a handle is the start of a drag, not a click.
    this.pointerDown = this.transform.axis === null ? {x: event.clientX, y: event.clientY} : null;
  }

  onPointerUp(event) {
    const down = this.pointerDown;
    this.pointerDown = null;
    if (!down || (event.button !== 0 && event.button !== 2)) return;
    if (Math.hypot(event.clientX - down.x, event.clientY - down.y) > CLICK_SLOP) return;
    const name = this.modelAt(event.clientX, event.clientY);
    if (event.button === 0) return this.select(name);
    // A right click on a model (a right drag zooms): its menu, as Gazebo's ModelRightMenu.
    if (name === null) return undefined;
    this.select(name);
    this.dispatchEvent(new CustomEvent('modelmenu', {detail: {name, x: event.clientX, y: event.clientY}}));
    return undefined;
  }

  // -- the model menu's View and camera entries --------------------------------------------
  // look: {transparent, wireframe, collisions}, each true or false; all false draws it as it is.
  setLook(name, look) {
    const model = this.models.get(name);
    if (!model) return;
    if (look.transparent || look.wireframe || look.collisions) this.looks.set(name, {...look});
    else this.looks.delete(name);
    this.applyLook(name);
    if (model.description.static) this.batchStale = true;
    this.requestRender();
  }

  lookOf(name) {
    return this.looks.get(name) || {transparent: false, wireframe: false, collisions: false};
  }

  applyLook(name) {
    const model = this.models.get(name);
    const look = this.lookOf(name);
    model.group.traverse((object) => {
      if (!object.isMesh || object.userData.collision) return;
      const material = object.material;
      if (material.userData.opacity === undefined) {
        material.userData.opacity = material.opacity;
        material.userData.transparent = material.transparent;
      }
      material.transparent = look.transparent || material.userData.transparent;
      material.opacity = look.transparent ? Math.min(0.5, material.userData.opacity) : material.userData.opacity;
      material.depthWrite = !look.transparent;
      material.wireframe = look.wireframe;
      material.needsUpdate = true;
    });
    for (const link of model.description.links) {
      const group = model.links.get(link.name);
      let shown = group.getObjectByName(group.name + '::collisions');
      if (look.collisions && !shown) {
        shown = buildCollisions(group.name + '::collisions', link.collisions || []);
        group.add(shown);
      }
      if (shown) shown.visible = look.collisions;
    }
  }

  // Gazebo's Move To: the camera turns to the model and comes near it.
  moveTo(name) {
    const model = this.models.get(name);
    if (model) this.frameObject(model.group);
  }

  // Gazebo's Follow: the camera goes where the model goes, until follow(null) (Esc).
  follow(name) {
    this.followed = name !== null && this.models.has(name) ? name : null;
    if (this.followed) this.moveTo(this.followed);
    this.dispatchEvent(new CustomEvent('follow', {detail: {name: this.followed}}));
  }

  modelAt(clientX, clientY) {
    const raycaster = new THREE.Raycaster();
    raycaster.setFromCamera(this.toNdc(clientX, clientY), this.camera);
    const groups = [...this.models.values()].map((model) => model.group);
    for (const hit of raycaster.intersectObjects(groups, true)) {
      let object = hit.object;
      while (object && object.userData.name === undefined) object = object.parent;
      if (object && hit.object.isMesh) return object.userData.name;
    }
    return null;
  }

  toNdc(clientX, clientY) {
    const rect = this.canvas.getBoundingClientRect();
    return new THREE.Vector2(((clientX - rect.left) / rect.width) * 2 - 1,
                             -((clientY - rect.top) / rect.height) * 2 + 1);
  }

  // -- the camera -----------------------------------------------------------------------
  frameAll() {
    const box = new THREE.Box3();
    for (const model of this.models.values()) box.expandByObject(model.group);
    if (box.isEmpty()) box.set(new THREE.Vector3(-3, -3, 0), new THREE.Vector3(3, 3, 1));
    const centre = box.getCenter(new THREE.Vector3());
    const size = Math.max(box.max.x - box.min.x, box.max.y - box.min.y, 4);
    this.orbit.target.copy(centre);
    this.camera.position.set(centre.x - 0.55 * size, centre.y - 0.75 * size, centre.z + 0.6 * size);
    this.orbit.update();
    this.requestRender();
  }

  // Look from pose [x, y, z, roll, pitch, yaw] (a world's <gui><camera><pose>: the camera
  // looks along its x axis), orbiting about the floor point it looks at.
  lookFrom(pose) {
    const [x, y, z, roll, pitch, yaw] = pose;
    const along = new THREE.Vector3(1, 0, 0).applyEuler(new THREE.Euler(roll, pitch, yaw, 'ZYX'));
    this.camera.position.set(x, y, z);
    const toFloor = along.z < -1e-3 ? z / -along.z : Infinity;
    this.orbit.target.copy(along).multiplyScalar(Math.min(toFloor, 20)).add(this.camera.position);
    this.orbit.update();
    this.requestRender();
  }

  // Turn towards object and come near enough that it fills about a third of the view.
  frameObject(object) {
    const box = new THREE.Box3().setFromObject(object);
    if (box.isEmpty()) return;
    const centre = box.getCenter(new THREE.Vector3());
    const radius = Math.max(box.getSize(new THREE.Vector3()).length() / 2, 0.1);
    const fit = 3 * radius / Math.tan(THREE.MathUtils.degToRad(this.camera.fov / 2));
    const from = this.camera.position.clone().sub(this.orbit.target);
    if (from.lengthSq() < 1e-9) from.set(-1, -1, 1);
    this.orbit.target.copy(centre);
    this.camera.position.copy(centre).add(from.setLength(Math.max(fit, this.camera.near * 10)));
    this.orbit.update();
    this.requestRender();
  }

  topView() {
    const target = this.orbit.target;
    const distance = Math.max(this.camera.position.distanceTo(target), 4);
    // Straight down, with +y (north) up the screen, as Gazebo's top view.
    this.camera.position.set(target.x, target.y - 1e-3, target.z + distance);
    this.orbit.update();
    this.requestRender();
  }

  screenPointOf(position) {
    const rect = this.canvas.getBoundingClientRect();
    const ndc = position.clone().project(this.camera);
    return {x: rect.left + (ndc.x + 1) / 2 * rect.width, y: rect.top + (1 - ndc.y) / 2 * rect.height};
  }

  // Where the middle of a model's shapes is on the screen, or null: for tests that click on it.
  modelPoint(name) {
    const model = this.models.get(name);
    if (!model) return null;
    const box = new THREE.Box3();
    // Where the last poses put it, drawn or not yet.
    model.group.updateMatrixWorld(true);
    model.group.traverse((object) => { if (object.isMesh) box.expandByObject(object); });
    return this.screenPointOf(box.isEmpty() ? model.group.position : box.getCenter(new THREE.Vector3()));
  }

  // Where on the screen the transform handle `axis` ('X', 'Y', 'XY', 'Z') of the selected
  // model can be grabbed, or null: for tests that drag it with a real mouse.
  handlePoint(axis) {
    if (!this.transform.object) return null;
    this.render();
    const picker = this.transform._gizmo.picker[this.transform.mode];
    picker.updateMatrixWorld(true);
    const raycaster = new THREE.Raycaster();
    const centre = this.screenPointOf(this.transform.object.getWorldPosition(new THREE.Vector3()));
    for (let radius = 2; radius < 200; radius += 2) {
      // Points about 3 pixels apart on each circle, so that no handle slips between them.
      const turns = Math.max(16, Math.ceil(2 * Math.PI * radius / 3));
      for (let turn = 0; turn < turns; turn += 1) {
        const angle = (turn / turns) * 2 * Math.PI;
        const x = centre.x + radius * Math.cos(angle);
        const y = centre.y + radius * Math.sin(angle);
        raycaster.setFromCamera(this.toNdc(x, y), this.camera);
        // As the controls pick: the first handle hit that they show.
        const hit = raycaster.intersectObject(picker, true).find((found) => found.object.visible);
        if (hit && hit.object.name === axis) return {x, y};
      }
    }
    return null;
  }
}
