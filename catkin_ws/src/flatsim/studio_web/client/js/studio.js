// What every panel shares: the connection, the 3D view, the latest state the
// simulator streamed, and the hooks through which panels add menu entries,
// toolbar buttons, tabs and actions. A panel is an ES module whose mount(studio)
// builds its part of the page; the studio itself holds no world of its own.
//
// The hooks exist before any panel mounts, so panels mount in any order:
//   studio.addAction(name, run, {mode, keys})  an action, for menus, buttons and keys: in one
//       mode ('world', 'model', 'building', a list of them) or, without mode, in every mode;
//       keys (['Ctrl+Z']) bind it in those modes. studio.run(name) runs the current mode's.
//   studio.keymap.bind(mode, key, name)        a key for an action (see keymap.js)
//   studio.menus.add(menu, {label, action, shortcut}), .addCheck(...)   the window's menu bar
//   studio.toolbar.add(element, {modes})       a toolbar button, shown only in those modes
//   studio.addTab(name)                        a tab of the left panel: its panel element
//   studio.on(event, handler)                  'modechange' {mode}, 'scene', 'poses', ...
// studio.mode is 'world', or the editor open ('model', 'building'; see editor_shell.js).
// A panel may leave a handle for the tests (studio.buildingEditor); no panel reads another's.

import {Keymap, MODES} from './keymap.js';
import {Menus} from './panels/menus.js';
import {Tabs} from './panels/tabs.js';
import {Toolbar} from './panels/toolbar.js';

export class Studio extends EventTarget {
  constructor(connection, view) {
    super();
    this.connection = connection;
    this.view = view;
    this.session = null;        // this page's session id (hello)
    this.scene = null;          // the last scene message
    this.poses = {};            // model -> pose, as last streamed
    this.status = null;
    this.leases = {};           // model -> session editing it
    this.skipped = [];
    this.actions = new Map();   // name -> Map(mode or '*' -> function), for menus, toolbar and keys
    this.mode = 'world';
    document.body.dataset.mode = this.mode;
    this.settings = {};         // what the hello says the panels draw with (building: the grid, ...)
    this.keymap = new Keymap();
    this.keymap.listen(this);
    this.menus = new Menus(document.querySelector('.menubar'));
    // Gazebo's order; Help would appear once a panel put something in it.
    for (const name of ['File', 'Edit', 'Camera', 'View', 'Window']) this.menus.menu(name);
    this.toolbar = new Toolbar(document.querySelector('.toolbar'), this);
    const tabs = new Tabs(document.querySelector('.left .tabs'), document.querySelector('.left .tab-panels'));
    this.addTab = (name) => tabs.add(name);
    this.ready = false;
    connection.on('hello', (message) => {
      this.session = message.session;
      if (message.building) this.settings.building = message.building;
      if (document.hidden) this.followStream();
    });
    // A tab out of sight takes no stream, so the simulator does no work for it.
    document.addEventListener('visibilitychange', () => this.followStream());
    connection.on('scene', (message) => {
      this.scene = message;
      this.poses = Object.fromEntries(message.models.map((model) => [model.name, model.pose]));
      view.setScene(message);
      this.emit('scene', message);
    });
    connection.on('poses', (message) => {
      Object.assign(this.poses, message.models);
      view.applyPoses(message.models, message.links);
      this.emit('poses', message);
      if (message.full && !this.ready) this.markReady();
    });
    connection.on('status', (message) => { this.status = message; this.emit('status', message); });
    connection.on('leases', (message) => { this.leases = message.leases; this.emit('leases', message); });
    connection.on('skipped', (message) => { this.skipped = message.items; this.emit('skipped', message); });
    view.addEventListener('select', (event) => this.emit('selection', event.detail));
  }

  followStream() {
    if (this.connection.isOpen) this.connection.request('stream', {on: !document.hidden});
  }

  emit(type, detail) {
    this.dispatchEvent(new CustomEvent(type, {detail}));
  }

  on(type, handler) {
    this.addEventListener(type, (event) => handler(event.detail));
  }

  markReady() {
    // Where the world's <gui><camera> looks from, as Gazebo's window first does.
    if (this.scene && this.scene.camera) this.view.lookFrom(this.scene.camera);
    else this.view.frameAll();
    this.ready = true;
    document.body.dataset.ready = 'true';
    this.emit('ready', {});
  }

  get selected() {
    return this.view.selected;
  }

  // Another page is editing this model (an edit here would be refused).
  editedElsewhere(model) {
    const holder = this.leases[model];
    return holder !== undefined && holder !== this.session;
  }

  // Send a command; a refusal is shown to the user. Resolves with the reply.
  async request(type, fields = {}) {
    const reply = await this.connection.request(type, fields);
    if (!reply.ok) this.notify(reply.message);
    return reply;
  }

  // Something refused or gone wrong: shown as an alert.
  notify(message) {
    this.emit('notice', {message});
  }

  // What the simulator did and said about it (a save, what it left out): shown as a message.
  inform(message) {
    this.emit('notice', {message, kind: 'info'});
  }

  // The world, or an editor: what the keymap and the toolbar follow.
  enterMode(mode) {
    if (!MODES.includes(mode)) throw new Error('no mode ' + mode);
    this.mode = mode;
    document.body.dataset.mode = mode;
    this.emit('modechange', {mode});
  }

  addAction(name, run, {mode = '*', keys = []} = {}) {
    if (!this.actions.has(name)) this.actions.set(name, new Map());
    const modes = this.actions.get(name);
    for (const one of mode === '*' ? ['*'] : [].concat(mode)) {
      if (one !== '*' && !MODES.includes(one)) throw new Error('no mode ' + one);
      if (modes.has(one)) throw new Error('action ' + name + ' is there already in mode ' + one);
      modes.set(one, run);
    }
    for (const key of keys) this.keymap.bind(mode, key, name);
  }

  // The action name does in mode (the current one by default), or null.
  action(name, mode = this.mode) {
    const modes = this.actions.get(name);
    if (!modes) return null;
    return modes.get(mode) || modes.get('*') || null;
  }

  run(name, ...args) {
    const action = this.action(name);
    if (action) return action(...args);
    return undefined;
  }
}
