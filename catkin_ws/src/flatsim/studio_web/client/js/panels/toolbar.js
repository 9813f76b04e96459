// The toolbar under the menus: Gazebo's selection, translation, rotation and scale
// modes (hotkeys Esc, t, r, s), copy and paste, and the top view. Each button is
// shown only in the modes it acts in: the world's tools are gone while an editor
// is open, so that no click reaches the world hidden behind it.

export class Toolbar {
  constructor(bar, studio) {
    this.bar = bar;
    this.parts = [];              // {element, modes}
    studio.on('modechange', ({mode}) => this.show(mode));
  }

  // element shown in modes (['world'] by default; '*' for every mode).
  add(element, {modes = ['world']} = {}) {
    this.parts.push({element, modes});
    this.bar.append(element);
    return element;
  }

  separator(options) {
    return this.add(Object.assign(document.createElement('span'), {className: 'separator'}), options);
  }

  show(mode) {
    for (const {element, modes} of this.parts) {
      element.hidden = !(modes === '*' || modes.includes(mode));
    }
  }
}

export function mount(studio) {
  const bar = studio.toolbar;
  const modeButtons = new Map();
  const button = (label, title, onClick, modes) => {
    const element = document.createElement('button');
    element.textContent = label;
    element.title = title;
    element.addEventListener('click', onClick);
    return bar.add(element, {modes});
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
  bar.separator();
  button('Copy', 'Copy the selected model (Ctrl+C)', () => studio.run('copy'));
  button('Paste', 'Paste a copy of it (Ctrl+V)', () => studio.run('paste'));
  bar.separator({modes: ['world', 'model']});
  // The Model Editor's model is drawn in the 3D view too.
  button('Top View', 'Look at the world from above', () => studio.view.topView(), ['world', 'model']);
}
