// The page's one keymap: (mode, key) -> the name of an action in studio.actions. One
// keydown listener on the window reads it, so that a key does one thing in each mode (the
// world, the Model Editor, the Building Editor) whatever panel it belongs to. No hotkey
// fires while a text field has the focus (what is typed is the field's) or a dialog is open.
// Keys are written as menus show them: 'Ctrl+Shift+S', 'Delete', 'Esc', 't'.

export const MODES = ['world', 'model', 'building'];

const ALIASES = {esc: 'Escape', del: 'Delete', space: ' '};

// 'Ctrl+Shift+z' for both the text 'Ctrl+Shift+Z' and a keydown of Ctrl, Shift and Z.
export function keyName({key, ctrl = false, alt = false, shift = false}) {
  const named = ALIASES[key.toLowerCase()] || key;
  const base = named.length === 1 ? named.toLowerCase() : named[0].toUpperCase() + named.slice(1);
  return (ctrl ? 'Ctrl+' : '') + (alt ? 'Alt+' : '') + (shift ? 'Shift+' : '') + base;
}

export function parseKey(text) {
  const parts = text.split('+');
  // 'Ctrl++' would be the plus key.
  const key = parts.pop() || '+';
  const modifiers = new Set(parts.map((part) => part.toLowerCase()));
  for (const modifier of modifiers) {
    if (!['ctrl', 'alt', 'shift'].includes(modifier)) throw new Error('unknown modifier in key ' + text);
  }
  return keyName({key, ctrl: modifiers.has('ctrl'), alt: modifiers.has('alt'), shift: modifiers.has('shift')});
}

export function eventKey(event) {
  return keyName({key: event.key, ctrl: event.ctrlKey || event.metaKey, alt: event.altKey,
                  shift: event.shiftKey});
}

// Whether the key goes to a field being typed in (any input, a list, a text area).
export function typing(target) {
  return target instanceof HTMLInputElement || target instanceof HTMLSelectElement ||
         target instanceof HTMLTextAreaElement || Boolean(target && target.isContentEditable);
}

export class Keymap {
  constructor() {
    this.bindings = new Map(MODES.map((mode) => [mode, new Map()]));
  }

  // mode: one of MODES, a list of them, or '*' for every mode. A key already bound to
  // another action in a mode is a mistake in the page's code, and said at once.
  bind(mode, key, action) {
    const name = parseKey(key);
    for (const one of mode === '*' ? MODES : [].concat(mode)) {
      const keys = this.bindings.get(one);
      if (!keys) throw new Error('no mode ' + one + ' (modes: ' + MODES.join(', ') + ')');
      const bound = keys.get(name);
      if (bound !== undefined && bound !== action) {
        throw new Error(name + ' in ' + one + ' is ' + bound + ' already, not ' + action);
      }
      keys.set(name, action);
    }
  }

  lookup(mode, key) {
    const keys = this.bindings.get(mode);
    return (keys && keys.get(parseKey(key))) || null;
  }

  // {mode: {key: action}}, for the docs and the tests.
  describe() {
    return Object.fromEntries([...this.bindings].map(([mode, keys]) => [mode, Object.fromEntries(keys)]));
  }

  // The action a keydown runs in mode, or null.
  actionFor(mode, event) {
    // A keydown without a key is the browser filling in a field, never a hotkey.
    if (!event.key || typing(event.target) || document.querySelector('dialog[open]')) return null;
    return this.bindings.get(mode).get(eventKey(event)) || null;
  }

  // Listen on the window, ahead of every other listener (capture), so that the browser's own
  // meaning of a bound key (Ctrl+S saves the page) never comes first.
  listen(studio) {
    window.addEventListener('keydown', (event) => {
      const action = this.actionFor(studio.mode, event);
      if (!action) return;
      event.preventDefault();
      event.stopPropagation();
      studio.run(action);
    }, true);
  }
}
