// The toolbar under the menus: Gazebo's selection, translation, rotation and scale
// modes (hotkeys Esc, t, r, s), copy and paste, and the top view.

export function mount(studio) {
  const bar = document.querySelector('.toolbar');
  const modeButtons = new Map();
  const button = (label, title, onClick) => {
    const element = document.createElement('button');
    element.textContent = label;
    element.title = title;
    element.addEventListener('click', onClick);
    bar.append(element);
    return element;
  };
  for (const [mode, label, key] of [['select', 'Selection Mode', 'Esc'],
                                    ['translate', 'Translation Mode', 't'],
                                    ['rotate', 'Rotation Mode', 'r'],
                                    ['scale', 'Scale Mode', 's']]) {
    const element = button(label, label + ' (' + key + ')', () => studio.run('setMode', mode));
    element.setAttribute('aria-pressed', String(mode === 'select'));
    element.setAttribute('aria-keyshortcuts', key === 'Esc' ? 'Escape' : key);
    modeButtons.set(mode, element);
  }
  studio.on('mode', ({mode}) => {
    for (const [name, element] of modeButtons) element.setAttribute('aria-pressed', String(name === mode));
  });
  bar.append(Object.assign(document.createElement('span'), {className: 'separator'}));
  button('Copy', 'Copy the selected model (Ctrl+C)', () => studio.run('copy'));
  button('Paste', 'Paste a copy of it (Ctrl+V)', () => studio.run('paste'));
  bar.append(Object.assign(document.createElement('span'), {className: 'separator'}));
  button('Top View', 'Look at the world from above', () => studio.view.topView());
  studio.toolbar = bar;
}
