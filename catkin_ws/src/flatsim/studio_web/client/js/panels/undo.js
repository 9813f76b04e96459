// Gazebo's Edit > Undo (Ctrl+Z) and Redo (Ctrl+Shift+Z). In the world the simulator holds the
// history, one for every window (flatsim.studio.history): the page asks for 'undo' or 'redo'
// and redraws what the simulator streams; the 'history' message says what each would do next.
// While an editor is open, they are the editor's own (EditorShell.undo), never the world's.

export function mount(studio) {
  studio.history = {undo: [], redo: []};
  const menus = studio.menus;
  const items = {};
  // First in the Edit menu, as in Gazebo.
  const edit = menus.menu('Edit');
  for (const [name, label, shortcut] of [['redo', 'Redo', 'Ctrl+Shift+Z'], ['undo', 'Undo', 'Ctrl+Z']]) {
    items[name] = menus.add('Edit', {label, shortcut, action: () => studio.run(name)});
    edit.prepend(items[name]);
  }

  const show = () => {
    for (const name of ['undo', 'redo']) {
      const next = studio.history[name][0];
      items[name].setAttribute('aria-disabled', String(!next));
      items[name].title = next ? (name === 'undo' ? 'Undo ' : 'Redo ') + next : '';
    }
  };
  show();
  studio.connection.on('history', (message) => {
    studio.history = {undo: message.undo, redo: message.redo};
    show();
    if (message.dropped.length) {
      studio.inform('Undo leaves out ' + message.dropped.join(', ') + ': changed outside the studio');
    }
  });

  const step = (name) => async () => {
    if (studio.editor) return studio.editor.undoOrRedo(name);
    // Nothing to do: as Gazebo's greyed entry, no request and no alert.
    if (!studio.history[name].length) return undefined;
    return studio.request(name);
  };
  // The Building Editor binds the same keys to its own (building_editor.js).
  for (const mode of ['world', 'model']) {
    studio.addAction('undo', step('undo'), {mode, keys: ['Ctrl+Z']});
    studio.addAction('redo', step('redo'), {mode, keys: ['Ctrl+Shift+Z']});
  }
}
