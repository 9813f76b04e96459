// Gazebo's Model Editor (Edit > Model Editor, Ctrl+M): a model of simple shapes, one link
// each (link_0, link_1, ...), as Gazebo's palette adds them. A link's inspector has Gazebo's
// tabs: Link (name, mass, pose), Visual (the shape's size and its Ambient, Diffuse, Specular
// and Emissive colours) and Collision (the same shape: flatsim uses one for both). The model
// is drawn in the 3D view as it is edited; the simulator checks and writes it on Save.
// The course's my_ball: Sphere, Radius 0.1, the four colours "1 1 1 1", Save As my_ball.
// Every edit can be undone (Edit > Undo, Ctrl+Z) and redone (Ctrl+Shift+Z) until New or Exit.

import * as THREE from 'three';
import {buildModel} from '../scene/shapes.js';
import {DesignHistory} from './design_history.js';
import {EditorShell, UNTITLED} from './editor_shell.js';
import {colourInput, labelledInput, makeButton, numberInput} from './dialogs.js';

const SIZES = {box: [1, 1, 1], sphere: [0.5], cylinder: [0.5, 1]};
const SIZE_LABELS = {box: ['X', 'Y', 'Z'], sphere: ['Radius'], cylinder: ['Radius', 'Length']};
// Gazebo/Grey, what the editor gives a new shape.
const GREY = {ambient: [0.3, 0.3, 0.3, 1], diffuse: [0.7, 0.7, 0.7, 1], specular: [0.01, 0.01, 0.01, 1],
              emissive: [0, 0, 0, 1]};
const MATERIAL = [['ambient', 'Ambient'], ['diffuse', 'Diffuse'], ['specular', 'Specular'], ['emissive', 'Emissive']];
const POSE = ['x', 'y', 'z', 'roll', 'pitch', 'yaw'];
// The preview's shapes are at least this big, whatever was typed (the simulator checks sizes).
const MIN_PREVIEW = 0.001;

function restingHeight(shape) {
  const size = shape.size.map((value) => Math.max(Math.abs(value), MIN_PREVIEW));
  if (shape.kind === 'box') return size[2] / 2;
  if (shape.kind === 'cylinder') return size[1] / 2;
  return size[0];
}

function heading(text) {
  const element = document.createElement('h2');
  element.textContent = text;
  return element;
}

export function mount(studio) {
  const palette = document.createElement('section');
  let design = null;
  let selected = -1;
  let preview = null;
  // Where the model is made and, on Exit, inserted: the floor point the view looked at when
  // the editor opened, so that a new shape is in sight, not hidden at the origin.
  let origin = [0, 0];
  // The world's model being edited (Edit model): Exit puts the saved model in its place.
  let replacing = null;
  const history = new DesignHistory();
  // Call before each edit: Undo comes back to the design as it is now.
  const remember = () => history.record({design, selected});

  // -- the palette -----------------------------------------------------------------------
  const shapes = document.createElement('div');
  shapes.className = 'button-row';
  shapes.setAttribute('role', 'group');
  shapes.setAttribute('aria-label', 'Simple Shapes');
  for (const kind of ['box', 'sphere', 'cylinder']) {
    shapes.append(makeButton(kind[0].toUpperCase() + kind.slice(1), () => addLink(kind), 'Add a ' + kind + ' link'));
  }
  const [nameLabel, nameInput] = labelledInput('Model name', {id: 'model-editor-name'});
  nameInput.addEventListener('change', () => { remember(); design.name = nameInput.value; shell.changed(); });
  const staticBox = document.createElement('input');
  staticBox.type = 'checkbox';
  staticBox.id = 'model-editor-static';
  const staticLabel = document.createElement('label');
  staticLabel.htmlFor = staticBox.id;
  staticLabel.textContent = 'Static';
  staticBox.addEventListener('change', () => { remember(); design.static = staticBox.checked; shell.changed(); });
  const modelFields = document.createElement('div');
  modelFields.className = 'form';
  modelFields.append(nameLabel, nameInput, staticLabel, staticBox);
  const linkList = document.createElement('ul');
  linkList.className = 'model-list';
  linkList.id = 'model-editor-links';
  const linksHeading = heading('Links');
  linksHeading.id = 'model-editor-links-heading';
  linkList.setAttribute('aria-labelledby', linksHeading.id);
  const inspector = document.createElement('div');
  inspector.className = 'inspector';
  inspector.setAttribute('role', 'group');
  inspector.setAttribute('aria-label', 'Link Inspector');
  palette.append(heading('Simple Shapes'), shapes, heading('Model'), modelFields, linksHeading, linkList,
                 inspector);

  const shell = new EditorShell(studio, {
    title: 'Model Editor', kind: 'model', command: 'save_model', defaultFolder: 'model_folder', palette,
    name: () => design.name,
    design: () => ({static: design.static, links: design.links.map((link) => ({
      name: link.name, mass: link.mass, pose: link.pose,
      shapes: [{kind: link.shape.kind, size: link.shape.size, ...link.shape.material}],
    }))}),
    savedAs: (reply) => { design.name = shell.saved.name; nameInput.value = design.name; },
    placeAt: () => origin,
    replaced: () => replacing,
    reset, undo: () => step('undo'), redo: () => step('redo'), opened: () => {
      const target = studio.view.orbit.target;
      origin = [target.x, target.y];
      reset();
    },
    closed: () => { reset(); showPreview(false); },
  });

  // -- the design ------------------------------------------------------------------------
  function reset() {
    replacing = null;
    design = {name: UNTITLED, static: false, links: [], counter: 0};
    selected = -1;
    history.clear();
    show();
  }

  function show() {
    nameInput.value = design.name;
    staticBox.checked = design.static;
    update();
  }

  // Undo or Redo (name): the design before the last edit, or after the last undone one.
  // Returns whether there was one.
  function step(name) {
    const state = history[name]({design, selected});
    if (!state) return false;
    ({design, selected} = state);
    selected = Math.min(selected, design.links.length - 1);
    show();
    return true;
  }

  function addLink(kind) {
    remember();
    const material = Object.fromEntries(Object.entries(GREY).map(([tag, rgba]) => [tag, [...rgba]]));
    design.links.push({name: 'link_' + design.counter++, mass: 1, pose: null,
                       shape: {kind, size: [...SIZES[kind]], material}});
    selected = design.links.length - 1;
    shell.changed();
    update();
    if (preview) studio.view.frameObject(preview);
  }

  function update() {
    showLinks();
    showInspector();
    showPreview(shell.active);
  }

  function showLinks() {
    linkList.replaceChildren(...design.links.map((link, index) => {
      const item = document.createElement('li');
      const button = makeButton(link.name, () => { selected = index; update(); });
      button.setAttribute('aria-selected', String(index === selected));
      item.append(button);
      return item;
    }));
  }

  // A field was edited: the model changed, and the view shows it (the inspector stays as it is).
  function edited() {
    shell.changed();
    showPreview(shell.active);
  }

  // -- the link inspector ----------------------------------------------------------------
  const numberField = (label, read, write) => numberInput(studio, label, read, (value) => {
    remember();
    write(value);
    edited();
  });

  const colourField = (label, link, tag) => {
    const field = colourInput(studio, label, () => link.shape.material[tag], (values) => {
      remember();
      link.shape.material[tag] = values;
      edited();
    });
    // Saved for Gazebo, but flatsim's camera draws no highlights: say so where it is typed.
    if (tag === 'specular') field[1].title += '; saved in the model for Gazebo, not used by flatsim\'s camera';
    return field;
  };

  function sizeFields(link) {
    const fields = [];
    SIZE_LABELS[link.shape.kind].forEach((label, index) => {
      fields.push(...numberField(label, () => link.shape.size[index], (value) => {
        link.shape.size[index] = value === null ? SIZES[link.shape.kind][index] : value;
      }));
    });
    return fields;
  }

  function form(...children) {
    const element = document.createElement('div');
    element.className = 'form';
    element.append(...children);
    return element;
  }

  let inspectorTab = 'Link';
  function showInspector() {
    const link = design.links[selected];
    inspector.hidden = !link;
    if (!link) return inspector.replaceChildren();
    const pose = () => link.pose || [0, 0, null, 0, 0, 0];
    const poseFields = POSE.flatMap((axis, index) => numberField(axis, () => pose()[index], (value) => {
      const next = link.pose ? [...link.pose] : [0, 0, restingHeight(link.shape), 0, 0, 0];
      next[index] = value === null ? (index === 2 ? restingHeight(link.shape) : 0) : value;
      link.pose = next;
    }));
    const panels = {
      Link: form(...numberField('Mass', () => link.mass, (value) => { link.mass = value === null ? 1 : value; }),
                 ...(() => {
                   const [label, input] = labelledInput('Name', {value: link.name});
                   input.addEventListener('change', () => {
                     remember();
                     link.name = input.value;
                     shell.changed();
                     showLinks();
                   });
                   return [label, input];
                 })(), ...poseFields),
      Visual: form(...sizeFields(link), ...MATERIAL.flatMap(([tag, label]) => colourField(label, link, tag))),
      Collision: form(...sizeFields(link)),
    };
    panels.Collision.title = 'flatsim uses the same shape for Visual and Collision';
    const tabs = document.createElement('div');
    tabs.setAttribute('role', 'tablist');
    tabs.setAttribute('aria-label', 'Link Inspector tabs');
    tabs.className = 'tabs';
    const title = heading('Link Inspector: ' + link.name);
    inspector.replaceChildren(title, tabs);
    for (const [name, panel] of Object.entries(panels)) {
      const tab = makeButton(name, () => { inspectorTab = name; showInspector(); });
      tab.setAttribute('role', 'tab');
      tab.id = 'model-editor-tab-' + name.toLowerCase();
      tab.setAttribute('aria-selected', String(name === inspectorTab));
      tabs.append(tab);
      panel.setAttribute('role', 'tabpanel');
      panel.setAttribute('aria-labelledby', tab.id);
      panel.hidden = name !== inspectorTab;
      inspector.append(panel);
    }
    inspector.append(makeButton('Delete Link', () => {
      remember();
      design.links.splice(selected, 1);
      selected = Math.min(selected, design.links.length - 1);
      shell.changed();
      update();
    }));
  }

  // -- the 3D view -----------------------------------------------------------------------
  function showPreview(visible) {
    const view = studio.view;
    if (preview) view.scene.remove(preview);
    preview = null;
    if (visible && design.links.length) {
      preview = buildModel({
        name: design.name, pose: [0, 0, 0, 0, 0, 0], static: design.static, sensors: [],
        links: design.links.map((link) => ({
          name: link.name, pose: link.pose || [0, 0, restingHeight(link.shape), 0, 0, 0],
          shapes: [{name: link.name + '::visual', shape: link.shape.kind, pose: [0, 0, 0, 0, 0, 0],
                    size: link.shape.size.map((value) => Math.max(Math.abs(value), MIN_PREVIEW)),
                    color: link.shape.material.diffuse}],
        })),
      }).group;
      preview.position.set(origin[0], origin[1], 0);
      preview.name = 'Model Editor: ' + design.name;
      view.scene.add(preview);
    }
    view.requestRender();
  }

  // Gazebo's Edit model (the model menu): the model as the simulator shows it, one link per
  // shape (the editor's links hold one shape each), on the floor where it stands.
  function editModel(name) {
    const model = studio.view.models.get(name);
    if (!model) return studio.notify('there is no model named ' + name);
    if (studio.editor) return studio.notify('Exit the ' + studio.editor.editor.title + ' first');
    const description = model.description;
    // Its sensors and plugins would not come back from the editor's shapes.
    if (description.kind === 'robot') {
      return studio.notify(name + ' is a robot from its URDF: edit its xacro, not its shapes here');
    }
    const [x, y, z, roll, pitch] = studio.poses[name] || description.pose;
    shell.open();
    origin = [x, y];
    // The model frame's height and tilt stay with the links: the editor's model stands on the floor.
    const base = new THREE.Matrix4().compose(new THREE.Vector3(0, 0, z),
      new THREE.Quaternion().setFromEuler(new THREE.Euler(roll, pitch, 0, 'ZYX')), new THREE.Vector3(1, 1, 1));
    const matrixOf = (pose) => new THREE.Matrix4().compose(new THREE.Vector3(pose[0], pose[1], pose[2]),
      new THREE.Quaternion().setFromEuler(new THREE.Euler(pose[3], pose[4], pose[5], 'ZYX')),
      new THREE.Vector3(1, 1, 1));
    for (const link of description.links) {
      link.shapes.forEach((shape, index) => {
        const matrix = base.clone().multiply(matrixOf(link.pose)).multiply(matrixOf(shape.pose));
        const at = new THREE.Vector3();
        const turn = new THREE.Quaternion();
        matrix.decompose(at, turn, new THREE.Vector3());
        const euler = new THREE.Euler().setFromQuaternion(turn, 'ZYX');
        const colour = [...shape.color];
        design.links.push({
          name: link.shapes.length > 1 ? link.name + '_' + index : link.name, mass: 1,
          pose: [at.x, at.y, at.z, euler.x, euler.y, euler.z].map((value) => Number(value.toFixed(6))),
          shape: {kind: shape.shape, size: [...shape.size],
                  material: {...Object.fromEntries(Object.entries(GREY).map(([tag, rgba]) => [tag, [...rgba]])),
                             ambient: colour, diffuse: [...colour]}},
        });
      });
    }
    design.counter = design.links.length;
    design.name = name;
    design.static = Boolean(description.static);
    nameInput.value = name;
    staticBox.checked = design.static;
    replacing = name;
    selected = design.links.length ? 0 : -1;
    update();
    if (preview) studio.view.frameObject(preview);
    return undefined;
  }
  studio.addAction('editModel', editModel);

  reset();
  studio.modelEditor = shell;
  studio.addAction('modelEditor', () => shell.open(), {keys: ['Ctrl+M']});
  studio.menus.add('Edit', {label: 'Model Editor', shortcut: 'Ctrl+M', action: () => studio.run('modelEditor')});
}
