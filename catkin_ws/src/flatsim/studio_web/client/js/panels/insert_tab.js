// Gazebo's Insert tab and the toolbar's simple shapes: every model on the model path, by
// its model.config name and grouped by folder as Gazebo lists them (a broken folder too,
// with what is wrong with it), and the box, sphere and cylinder. Pick one, then click on
// the floor in the view: the simulator spawns it there, and it comes back in the stream.

import * as THREE from 'three';
import {makeButton} from './dialogs.js';

const SHAPES = [['box', 'Box'], ['sphere', 'Sphere'], ['cylinder', 'Cylinder']];
// A press that moves the pointer further than this (pixels) is a look around, not a drop.
const DROP_SLOP = 5;
const FLOOR = new THREE.Plane(new THREE.Vector3(0, 0, 1), 0);

// Where on the floor (z = 0) the pointer points, or null above the horizon.
export function floorPoint(view, clientX, clientY) {
  const raycaster = new THREE.Raycaster();
  raycaster.setFromCamera(view.toNdc(clientX, clientY), view.camera);
  return raycaster.ray.intersectPlane(FLOOR, new THREE.Vector3());
}

export function mount(studio) {
  const view = studio.view;
  const panel = studio.addTab('Insert');
  const placingLine = document.createElement('p');
  placingLine.setAttribute('role', 'status');
  placingLine.setAttribute('aria-label', 'Placing');
  placingLine.className = 'placing';
  const lists = document.createElement('div');
  panel.append(placingLine, lists);
  let placing = null;             // {label, fields} of what the next click drops
  let pressed = null;
  const marker = new THREE.Mesh(new THREE.RingGeometry(0.15, 0.22, 32),
                                new THREE.MeshBasicMaterial({color: 0xf39c12}));
  marker.visible = false;
  view.scene.add(marker);

  const stopPlacing = () => {
    placing = null;
    placingLine.textContent = '';
    marker.visible = false;
    view.canvas.classList.remove('placing');
    view.requestRender();
  };

  const startPlacing = (label, fields) => {
    placing = {label, fields};
    placingLine.textContent = 'Click on the floor in the view to place ' + label + ' (Esc cancels)';
    view.canvas.classList.add('placing');
  };

  const group = (title, items) => {
    const id = 'insert-' + title.toLowerCase().replace(/\W+/g, '-');
    const heading = document.createElement('h2');
    heading.id = id;
    heading.textContent = title;
    const list = document.createElement('ul');
    list.className = 'model-list';
    list.setAttribute('aria-labelledby', id);
    list.append(...items);
    return [heading, list];
  };

  const modelItem = (model) => {
    const item = document.createElement('li');
    const button = makeButton(model.name, () => {
      // A broken model goes straight to the simulator, whose refusal says what is wrong.
      if (model.problem) studio.request('insert', {model: model.folder});
      else startPlacing(model.name, {model: model.folder});
    }, model.description || model.uri);
    if (model.problem) {
      const problem = document.createElement('span');
      problem.className = 'problem';
      problem.textContent = ' (cannot be inserted: ' + model.problem + ')';
      button.append(problem);
    }
    item.append(button);
    return item;
  };

  const show = ({paths, models}) => {
    const shapes = SHAPES.map(([shape, label]) => {
      const item = document.createElement('li');
      item.append(makeButton(label, () => startPlacing(label, {shape})));
      return item;
    });
    const parts = group('Simple Shapes', shapes);
    for (const path of paths) {
      const here = models.filter((model) => model.path === path);
      if (here.length) parts.push(...group(path, here.map(modelItem)));
    }
    lists.replaceChildren(...parts);
  };

  const refresh = async () => {
    const reply = await studio.request('model_path');
    if (reply.ok) show(reply);
  };
  studio.connection.on('open', refresh);
  studio.connection.on('model_path', show);

  for (const [shape, label] of SHAPES) {
    const button = makeButton(label, () => startPlacing(label, {shape}), 'Insert a ' + shape + ' (click on the floor)');
    studio.toolbar.add(button, {modes: ['world']});
  }

  // Ahead of the view's own handlers (capture), so that a drop neither selects nor orbits.
  const section = view.canvas.parentElement;
  section.addEventListener('pointermove', (event) => {
    if (!placing) return;
    const point = floorPoint(view, event.clientX, event.clientY);
    marker.visible = point !== null;
    if (point) marker.position.set(point.x, point.y, 0.005);
    view.requestRender();
  }, true);
  section.addEventListener('pointerdown', (event) => {
    if (!placing || event.button !== 0 || studio.mode !== 'world') return;
    pressed = {x: event.clientX, y: event.clientY};
    event.stopPropagation();
  }, true);
  section.addEventListener('pointerup', async (event) => {
    if (!placing || !pressed) return;
    event.stopPropagation();
    const moved = Math.hypot(event.clientX - pressed.x, event.clientY - pressed.y);
    pressed = null;
    const point = floorPoint(view, event.clientX, event.clientY);
    if (moved > DROP_SLOP || !point) return;
    const {fields} = placing;
    stopPlacing();
    const reply = await studio.request('insert', {...fields, at: [point.x, point.y]});
    if (reply.ok) studio.inform('Inserted ' + reply.name);
  }, true);
  // Esc (Selection Mode) cancels a placing, and so does an editor opening: the world it would
  // drop into is hidden then.
  studio.on('mode', ({mode}) => { if (placing && mode === 'select') stopPlacing(); });
  studio.on('modechange', () => { if (placing) stopPlacing(); });
  studio.insertTab = {refresh, startPlacing};
}
