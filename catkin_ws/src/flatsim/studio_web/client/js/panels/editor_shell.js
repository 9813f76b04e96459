// What Gazebo's Model Editor and Building Editor share: while one is open it takes the
// left column (its palette) and the menu bar (File: New, Save, Save As, Exit), and its
// Save As dialog ("Save Model": Model Name, Location, Browse) writes the model folder
// through the simulator. Exit puts the last saved model into the world, as Gazebo's does.
// The editor's kind is its mode (studio.mode while it is open): File's keys are bound in it.
// An editor module gives: title, kind ('model' | 'building'), command ('save_model' ...),
// defaultFolder (the 'places' field), palette (an element), design() (the command's
// fields), and reset(), opened(), closed() hooks; placeAt(), if given, the floor point [x, y]
// where Exit inserts the saved model; replaced(), if given, the world's model it replaces;
// undo() and redo(), if given, its Edit > Undo and Redo (Ctrl+Z, Ctrl+Shift+Z), which then
// undo the editor's edits and never the world's.

import {Menus} from './menus.js';
import {ask, chooseFolder, labelledInput, makeButton} from './dialogs.js';

export const UNTITLED = 'Untitled';

export class EditorShell {
  constructor(studio, editor) {
    this.studio = studio;
    this.editor = editor;
    this.active = false;
    this.dirty = false;
    this.saved = null;              // {name, folder (the parent), model (its own folder)}
    this.mainBar = document.querySelector('.menubar');
    this.bar = document.createElement('header');
    this.bar.className = 'menubar';
    this.bar.setAttribute('role', 'menubar');
    this.bar.setAttribute('aria-label', editor.title + ' menu bar');
    this.bar.hidden = true;
    this.mainBar.after(this.bar);
    // The editor's own menu bar; the editor may add to it (an Edit menu).
    const menus = this.menus = new Menus(this.bar);
    // The File menu's keys, in this editor's mode only.
    const mode = editor.kind;
    studio.addAction('save', () => this.save(), {mode, keys: ['Ctrl+S']});
    studio.addAction('saveAs', () => this.saveAs(), {mode, keys: ['Ctrl+Shift+S']});
    studio.addAction('exit', () => this.exit(), {mode, keys: ['Ctrl+X']});
    menus.add('File', {label: 'New', action: () => this.newDesign()});
    menus.add('File', {label: 'Save', shortcut: 'Ctrl+S', action: () => this.save()});
    menus.add('File', {label: 'Save As', shortcut: 'Ctrl+Shift+S', action: () => this.saveAs()});
    menus.add('File', {label: 'Exit ' + editor.title, shortcut: 'Ctrl+X', action: () => this.exit()});
    if (editor.undo) {
      menus.add('Edit', {label: 'Undo', shortcut: 'Ctrl+Z', action: () => this.undoOrRedo('undo')});
      menus.add('Edit', {label: 'Redo', shortcut: 'Ctrl+Shift+Z', action: () => this.undoOrRedo('redo')});
    }
    editor.palette.hidden = true;
    editor.palette.setAttribute('role', 'region');
    editor.palette.setAttribute('aria-label', editor.title);
    editor.palette.classList.add('editor-palette');
    document.querySelector('.left').prepend(editor.palette);
  }

  open() {
    if (this.studio.editor) {
      const other = this.studio.editor.editor.title;
      if (this.studio.editor !== this) this.studio.notify('Exit the ' + other + ' first');
      return;
    }
    this.studio.editor = this;
    this.active = true;
    this.showParts(true);
    // The keymap and the toolbar follow: the world's keys and tools wait until the editor closes.
    this.studio.enterMode(this.editor.kind);
    this.editor.opened();
  }

  showParts(editing) {
    this.mainBar.hidden = editing;
    this.bar.hidden = !editing;
    for (const part of document.querySelectorAll('.left > :not(.editor-palette)')) part.hidden = editing;
    this.editor.palette.hidden = !editing;
  }

  changed() {
    this.dirty = true;
  }

  // The studio's undo and redo actions, while this editor is open.
  undoOrRedo(name) {
    if (this.editor[name] && this.editor[name]()) this.changed();
  }

  async newDesign() {
    if (this.dirty && !(await this.discardAsked())) return;
    this.release();
    this.editor.reset();
    this.dirty = false;
  }

  async discardAsked() {
    return (await ask({title: 'New', text: 'Discard the changes not saved?',
                       buttons: [{label: 'Cancel', value: null}, {label: 'Discard', value: true}]})) === true;
  }

  // Save over the last save, or ask where first (Save As).
  save() {
    if (!this.saved) return this.saveAs();
    return this.write(this.saved.name, this.saved.folder, true);
  }

  async saveAs() {
    const places = await this.studio.request('places');
    if (!places.ok) return false;
    let folder = this.saved ? this.saved.folder : places[this.editor.defaultFolder];
    const named = this.saved ? this.saved.name : this.editor.name();
    const [nameLabel, name] = labelledInput('Model Name:', {value: named});
    const [whereLabel, where] = labelledInput('Location:', {value: folder});
    where.readOnly = true;
    const browse = makeButton('Browse', async () => {
      const chosen = await chooseFolder(this.studio, folder);
      if (chosen) where.value = folder = chosen;
    });
    const grid = document.createElement('div');
    grid.className = 'form';
    grid.append(nameLabel, name, whereLabel, where, document.createElement('span'), browse);
    // The dialog stays open until the simulator has saved, so a refused name can be put right.
    const pressed = await ask({
      title: 'Save Model',
      text: 'Pick a name and a location for your model.\n\nAll the model files will be saved in the model folder.',
      body: [grid], buttons: [{label: 'Cancel', value: null}, {label: 'Save', value: 'save', primary: true}],
      check: () => {
        if (name.value.trim()) return this.write(name.value.trim(), folder, false);
        this.studio.notify('Please give your model a non-empty name.');
        return false;
      },
    });
    return pressed === 'save';
  }

  async write(name, folder, overwrite) {
    const fields = {...this.editor.design(), name, folder, overwrite};
    const reply = await this.studio.request(this.editor.command, fields);
    if (!reply.ok) return false;
    if (!reply.saved) {
      const again = await ask({title: 'Files Exist', text: reply.message, buttons: [
        {label: 'Cancel', value: null}, {label: 'Save', value: true, primary: true}]});
      return again ? this.write(name, folder, true) : false;
    }
    this.saved = {name, folder, model: reply.folder};
    this.dirty = false;
    if (this.editor.savedAs) this.editor.savedAs(reply);
    this.studio.inform('Saved ' + name + ' in ' + reply.folder);
    return true;
  }

  async exit() {
    if (this.dirty || !this.saved) {
      const choice = await ask({
        title: 'Save Changes', text: 'Save Changes before exiting?',
        buttons: [{label: 'Cancel', value: null}, {label: "Don't Save, Exit", value: 'discard'},
                  {label: 'Save and Exit', value: 'save', primary: true}],
      });
      if (choice === null) return;
      if (choice === 'save' && !(await this.save())) return;
    }
    const inserted = this.saved;
    // The Model Editor's model goes where it was made; a building at its own pose.
    const at = this.editor.placeAt ? this.editor.placeAt() : null;
    // A model opened from the world (Edit model) goes back in its own place, as in Gazebo.
    const replaced = this.editor.replaced ? this.editor.replaced() : null;
    this.close();
    if (inserted) {
      if (replaced) await this.studio.request('delete', {model: replaced});
      const reply = await this.studio.request('insert', {model: inserted.model, ...(at ? {at} : {})});
      if (reply.ok) this.studio.inform('Inserted ' + reply.name + ' into the world');
    }
  }

  close() {
    this.release();
    this.editor.reset();
    this.saved = null;
    this.dirty = false;
    this.active = false;
    this.studio.editor = null;
    this.showParts(false);
    this.studio.enterMode('world');
    this.editor.closed();
  }

  release() {
    if (this.saved) this.studio.connection.request('editor_closed', {editor: this.editor.kind});
    this.saved = null;
  }
}
