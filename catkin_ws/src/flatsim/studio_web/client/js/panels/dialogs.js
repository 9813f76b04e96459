// Gazebo's modal dialogs: a question with its buttons (ask), and the folder chooser
// (chooseFolder, Gazebo's "Open Directory") that browses the simulator's folders and
// picks one, which lets files be saved there for this run.

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
// the simulator may save in) or null.
export async function chooseFolder(studio, start) {
  let current = null;
  const where = document.createElement('output');
  where.setAttribute('aria-label', 'Folder');
  const up = makeButton('Up', () => show(current && current.parent), 'The folder that holds this one');
  const list = document.createElement('ul');
  list.className = 'folder-list';
  list.setAttribute('aria-label', 'Folders');
  const show = async (path) => {
    if (!path) return;
    const reply = await studio.request('list_folder', {path});
    if (!reply.ok) return;
    current = reply;
    where.value = reply.path;
    up.disabled = !reply.parent;
    list.replaceChildren(...reply.folders.map((name) => {
      const item = document.createElement('li');
      item.append(makeButton(name, () => show(reply.path.replace(/\/$/, '') + '/' + name)));
      return item;
    }));
  };
  const header = document.createElement('div');
  header.className = 'chooser-path';
  header.append(up, where);
  const opened = ask({
    title: 'Open Directory', body: [header, list],
    buttons: [{label: 'Cancel', value: null}, {label: 'Choose', value: 'choose', primary: true}],
    check: async () => current !== null && (await studio.request('pick_folder', {path: current.path})).ok,
  });
  await show(start);
  if (current === null) await show('/');
  return (await opened) === 'choose' ? current.path : null;
}
