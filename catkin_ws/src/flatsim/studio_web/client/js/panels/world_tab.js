// Gazebo's World tab: the models, and the selected model's pose (x, y, z,
// roll, pitch, yaw) in fields that move the model when edited. The list and
// the fields show what the simulator streams; a field being typed in is left alone.

import {namedList} from './elements.js';

const FIELDS = ['x', 'y', 'z', 'roll', 'pitch', 'yaw'];
const DECIMALS = 3;

export function mount(studio) {
  const panel = studio.addTab('World');
  const [heading, list] = namedList('models-heading', 'Models', 'model-list');
  panel.append(heading, list);
  const rows = new Map();         // model -> {item, button, note, fields}

  const poseFields = (name) => {
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
      group.append(label, input);
      inputs[field] = input;
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
