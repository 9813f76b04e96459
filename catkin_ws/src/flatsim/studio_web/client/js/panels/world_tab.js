// Gazebo's World tab: the models, and the selected model's pose (x, y, z,
// roll, pitch, yaw) in fields that move the model when edited. The list and
// the fields show what the simulator streams; a field being typed in is left alone.

import {namedList} from './elements.js';

const FIELDS = ['x', 'y', 'z', 'roll', 'pitch', 'yaw'];
const DECIMALS = 3;
// What flatsim does not apply to a model that moves (a ball, a robot, a dynamic box): it
// simulates the plane, so such a model stands on the ground under it and turns about z only.
const PLANAR_ONLY = ['z', 'roll', 'pitch'];
export const NOT_APPLIED = 'flatsim is 2D: a moving model stands on the ground and turns about z ' +
  'only, so its z, roll and pitch are not applied';

export function mount(studio) {
  const panel = studio.addTab('World');
  const [heading, list] = namedList('models-heading', 'Models', 'model-list');
  panel.append(heading, list);
  const rows = new Map();         // model -> {item, button, note, fields}

  const moves = (name) => {
    const model = studio.scene && studio.scene.models.find((each) => each.name === name);
    return Boolean(model && !model.static);
  };

  const poseFields = (name) => {
    const planar = moves(name);
    const group = document.createElement('div');
    group.className = 'pose-fields';
    group.setAttribute('role', 'group');
    group.setAttribute('aria-label', name + ' pose');
    const inputs = {};
    for (const field of FIELDS) {
      const label = document.createElement('label');
      label.textContent = field;
      const input = document.createElement('input');
      input.type = 'number';
      input.step = field === 'x' || field === 'y' || field === 'z' ? '0.1' : '0.05';
      input.setAttribute('aria-label', field);
      label.htmlFor = input.id = 'pose-' + name + '-' + field;
      input.addEventListener('change', () => edit(name, inputs));
      if (planar && PLANAR_ONLY.includes(field)) {
        // Shown, never taken: a value typed here would be dropped without a word.
        input.disabled = true;
        input.title = NOT_APPLIED;
        input.setAttribute('aria-describedby', 'pose-' + name + '-not-applied');
      }
      group.append(label, input);
      inputs[field] = input;
    }
    if (planar) {
      const note = document.createElement('p');
      note.className = 'not-applied';
      note.id = 'pose-' + name + '-not-applied';
      note.textContent = NOT_APPLIED;
      group.append(note);
    }
    return {group, inputs};
  };

  const edit = async (name, inputs) => {
    const values = FIELDS.map((field) => inputs[field].value.trim());
    if (values.some((value) => value === '' || !Number.isFinite(Number(value)))) {
      studio.notify('Each pose field of ' + name + ' needs a number');
      showPose(name, true);
      return;
    }
    const pose = values.map(Number);
    const reply = await studio.request('set_pose', {model: name, pose});
    if (reply.ok) studio.connection.request('release', {model: name});
    // Refused: the fields show where the model is, even the one still being typed in.
    else showPose(name, true);
  };

  const showPose = (name, evenTyped = false) => {
    const row = rows.get(name);
    const pose = studio.poses[name];
    if (!row || !row.fields || !pose) return;
    FIELDS.forEach((field, index) => {
      const input = row.fields.inputs[field];
      if (evenTyped || document.activeElement !== input) input.value = pose[index].toFixed(DECIMALS);
    });
  };

  const showSelection = (name) => {
    for (const [model, row] of rows) {
      const selected = model === name;
      row.button.setAttribute('aria-selected', String(selected));
      if (selected && !row.fields) {
        row.fields = poseFields(model);
        row.item.append(row.fields.group);
        showPose(model);
      } else if (!selected && row.fields) {
        row.fields.group.remove();
        row.fields = null;
      }
    }
  };

  const showLeases = () => {
    for (const [model, row] of rows) {
      row.note.textContent = studio.editedElsewhere(model) ? 'being edited in another window' : '';
    }
  };

  studio.on('scene', (scene) => {
    list.replaceChildren();
    rows.clear();
    for (const model of scene.models) {
      const item = document.createElement('li');
      const button = document.createElement('button');
      button.textContent = model.name;
      button.setAttribute('aria-selected', 'false');
      button.addEventListener('click', () => studio.view.select(model.name));
      const note = document.createElement('span');
      note.className = 'editing';
      button.append(note);
      item.append(button);
      list.append(item);
      rows.set(model.name, {item, button, note, fields: null});
    }
    showSelection(studio.selected);
    showLeases();
  });
  studio.on('selection', ({name}) => showSelection(name));
  studio.on('poses', (message) => {
    const name = studio.selected;
    if (name && (message.full || name in message.models)) showPose(name);
  });
  studio.on('leases', showLeases);
}
