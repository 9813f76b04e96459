// Gazebo's modal dialogs: a question with its buttons (ask), and the folder chooser
// (chooseFolder, Gazebo's "Open Directory") that browses the simulator's folders and
// picks one, which lets files be saved there for this run; and the editors' labelled fields.

let dialogs = 0;

export function makeButton(label, onClick, title = '') {
  const element = document.createElement('button');
  element.type = 'button';
  element.textContent = label;
  if (title) element.title = title;
  element.addEventListener('click', onClick);
  return element;
}

// A text or number input with its label: [label element, input].
export function labelledInput(text, {type = 'text', value = '', step = 'any', id = null} = {}) {
  const input = document.createElement('input');
  input.type = type;
  if (type === 'number') input.step = step;
  input.value = value;
  input.id = id || 'field-' + (++dialogs);
  const label = document.createElement('label');
  label.textContent = text;
  label.htmlFor = input.id;
  return [label, input];
}

// A number field of an editor's inspector: write(value) takes what was typed, or null for
// an emptied field. Only what is no number is refused here: a size that makes no model (a
// negative radius) is the simulator's to refuse on Save, where it says what is wrong.
export function numberInput(studio, label, read, write) {
  const shown = () => (read() === null ? '' : String(Number(read().toFixed(6))));
  const [labelElement, input] = labelledInput(label, {type: 'number', value: shown()});
  input.addEventListener('change', () => {
    const text = input.value.trim();
    if (text !== '' && !Number.isFinite(Number(text))) {
      studio.notify(label + ' needs a number');
      input.value = shown();
      return;
    }
    write(text === '' ? null : Number(text));
  });
  return [labelElement, input];
}

// A colour field, "red green blue alpha" each from 0 to 1 as SDF writes it (alpha may be left out).
export function colourInput(studio, label, read, write) {
  const [labelElement, input] = labelledInput(label, {value: read().join(' ')});
  input.title = 'red green blue alpha, each from 0 to 1';
  input.addEventListener('change', () => {
    const values = input.value.trim().split(/[\s,]+/).map(Number);
    if (values.length === 3) values.push(1);
    if (values.length !== 4 || !values.every(Number.isFinite)) {
      studio.notify(label + ' needs four numbers: red green blue alpha');
      input.value = read().join(' ');
      return;
    }
    write(values);
  });
  return [labelElement, input];
}

// Show a modal dialog titled title, with text, body elements and buttons ({label, value,
// primary}). Resolves with the value of the button pressed, or null for Esc. check(value),
// if given, may keep the dialog open by resolving false (a name still missing, a save the
// simulator refused), so that nothing typed is lost.
export function ask({title, text = '', body = [], buttons, check = null}) {
  return new Promise((resolve) => {
    const dialog = document.createElement('dialog');
    const heading = document.createElement('h2');
    heading.id = 'dialog-' + (++dialogs);
    heading.textContent = title;
    dialog.setAttribute('aria-labelledby', heading.id);
    dialog.append(heading);
    for (const paragraph of text ? text.split('\n\n') : []) {
      const line = document.createElement('p');
      line.textContent = paragraph;
      dialog.append(line);
    }
    dialog.append(...body);
    let finished = false;
    const finish = (value) => {
      if (finished) return;
      finished = true;
      dialog.close();
      dialog.remove();
      resolve(value);
    };
    const row = document.createElement('div');
    row.className = 'buttons';
    for (const {label, value, primary} of buttons) {
      const element = makeButton(label, async () => {
        if (value !== null && check && !(await check(value))) return;
        finish(value);
      });
      if (primary) element.classList.add('primary');
      row.append(element);
    }
    dialog.append(row);
    dialog.addEventListener('cancel', (event) => {
      event.preventDefault();
      finish(null);
    });
    document.body.append(dialog);
    dialog.showModal();
  });
}

// Browse the simulator's folders from start; resolves with the folder chosen (now one
// the simulator may save in) or null. It lists a folder's .world files too, greyed, so
// that the worlds there are seen; Home goes to the home folder, New Folder makes one.
export async function chooseFolder(studio, start) {
  let current = null;
  const where = document.createElement('output');
  where.setAttribute('aria-label', 'Folder');
  const up = makeButton('Up', () => show(current && current.parent), 'The folder that holds this one');
  // Until the first folder is listed there is nothing to go up from.
  up.disabled = true;
  // No path: the simulator lists its home folder.
  const homeButton = makeButton('Home', () => show(''), 'Your home folder');
  const newFolder = makeButton('New Folder', () => makeFolder(), 'Make a folder in this one');
  const list = document.createElement('ul');
  list.className = 'folder-list';
  list.setAttribute('aria-label', 'Folders');
  const show = async (path) => {
    if (path === null || path === undefined) return false;
    const reply = await studio.request('list_folder', path ? {path} : {});
    if (!reply.ok) return false;
    current = reply;
    where.value = reply.path;
    up.disabled = !reply.parent;
    const folders = reply.folders.map((name) => {
      const item = document.createElement('li');
      item.append(makeButton(name, () => show(reply.path.replace(/\/$/, '') + '/' + name)));
      return item;
    });
    const files = reply.files.map((name) => {
      const item = document.createElement('li');
      item.className = 'file';
      item.textContent = name;
      return item;
    });
    list.replaceChildren(...folders, ...files);
    return true;
  };
  const makeFolder = async () => {
    if (!current) return;
    const [label, input] = labelledInput('Folder name:');
    const grid = document.createElement('div');
    grid.className = 'form';
    grid.append(label, input);
    let made = null;
    const pressed = await ask({
      title: 'New Folder', text: 'A new folder in ' + current.path, body: [grid],
      buttons: [{label: 'Cancel', value: null}, {label: 'Create', value: 'create', primary: true}],
      check: async () => {
        const reply = await studio.request('make_folder', {path: current.path, name: input.value});
        made = reply.ok ? reply.path : null;
        return reply.ok;
      },
    });
    if (pressed === 'create' && made) await show(made);
  };
  const header = document.createElement('div');
  header.className = 'chooser-path';
  header.append(up, homeButton, newFolder, where);
  const opened = ask({
    title: 'Open Directory', body: [header, list],
    buttons: [{label: 'Cancel', value: null}, {label: 'Choose', value: 'choose', primary: true}],
    check: async () => current !== null && (await studio.request('pick_folder', {path: current.path})).ok,
  });
  if (!(await show(start))) await show('');
  return (await opened) === 'choose' ? current.path : null;
}
