// The keymap's names and bindings, without a page: node --test test/
import {test} from 'node:test';
import assert from 'node:assert/strict';

import {Keymap, MODES, eventKey, parseKey} from '../client/js/keymap.js';

test('a key as menus write it and as a keydown gives it have one name', () => {
  assert.equal(parseKey('Ctrl+Shift+Z'), eventKey({key: 'Z', ctrlKey: true, shiftKey: true}));
  assert.equal(parseKey('Ctrl+z'), eventKey({key: 'z', ctrlKey: false, metaKey: true}));
  assert.equal(parseKey('Esc'), eventKey({key: 'Escape'}));
  assert.equal(parseKey('Delete'), eventKey({key: 'Delete'}));
  assert.notEqual(parseKey('Ctrl+Z'), parseKey('Ctrl+Shift+Z'));
  assert.notEqual(parseKey('t'), parseKey('Ctrl+T'));
  assert.throws(() => parseKey('Hyper+Z'), /unknown modifier in key Hyper\+Z/);
});

test('a key does one thing in each mode, and a second meaning in one mode is refused', () => {
  const keymap = new Keymap();
  keymap.bind('world', 'Delete', 'delete');
  keymap.bind('building', 'Delete', 'deleteSelected');
  keymap.bind('*', 'Ctrl+B', 'buildingEditor');
  assert.equal(keymap.lookup('world', 'Delete'), 'delete');
  assert.equal(keymap.lookup('building', 'Delete'), 'deleteSelected');
  assert.equal(keymap.lookup('model', 'Delete'), null);
  for (const mode of MODES) assert.equal(keymap.lookup(mode, 'Ctrl+b'), 'buildingEditor');
  assert.throws(() => keymap.bind('world', 'delete', 'undo'), /Delete in world is delete already, not undo/);
  assert.throws(() => keymap.bind('attic', 'x', 'exit'), /no mode attic/);
  // The same binding again is no conflict.
  keymap.bind(['world', 'model'], 'Ctrl+B', 'buildingEditor');
  assert.deepEqual(keymap.describe().building, {Delete: 'deleteSelected', 'Ctrl+b': 'buildingEditor'});
});
