// What every panel shares: the connection, the 3D view, the latest state the
// simulator streamed, and the hooks through which panels add menu entries,
// toolbar buttons, tabs and actions. A panel is an ES module whose mount(studio)
// builds its part of the page; the studio itself holds no world of its own.

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
    this.actions = new Map();   // name -> function, for menus, toolbar and hotkeys
    this.ready = false;
    connection.on('hello', (message) => {
      this.session = message.session;
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

  addAction(name, run) {
    this.actions.set(name, run);
  }

  run(name, ...args) {
    const action = this.actions.get(name);
    if (action) return action(...args);
    return undefined;
  }
}
