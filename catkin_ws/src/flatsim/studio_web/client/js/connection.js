// The studio's protocol from the page's side: one WebSocket to the simulator.
// on(type, handler) hears the server's messages (hello, scene, skipped, poses,
// status, leases, scans, camera_image); request(type, fields) sends a command
// and resolves with its reply ({ok, message, ...}) whatever the answer.

export class Connection {
  constructor(token) {
    this.token = token;
    this.handlers = new Map();
    this.pending = new Map();
    this.nextId = 1;
    this.socket = null;
  }

  on(type, handler) {
    if (!this.handlers.has(type)) this.handlers.set(type, []);
    this.handlers.get(type).push(handler);
  }

  emit(type, message) {
    for (const handler of this.handlers.get(type) || []) handler(message);
  }

  open() {
    const url = new URL('/ws', window.location.href);
    url.protocol = url.protocol === 'https:' ? 'wss:' : 'ws:';
    url.search = new URLSearchParams({token: this.token}).toString();
    const socket = new WebSocket(url);
    socket.binaryType = 'arraybuffer';
    socket.addEventListener('open', () => this.emit('open', {}));
    socket.addEventListener('close', (event) => {
      for (const resolve of this.pending.values()) {
        resolve({ok: false, message: 'the connection to the simulator is closed'});
      }
      this.pending.clear();
      this.emit('close', {code: event.code, reason: event.reason});
    });
    socket.addEventListener('message', (event) => this.receive(event.data));
    this.socket = socket;
  }

  receive(data) {
    if (data instanceof ArrayBuffer) {
      const view = new DataView(data);
      const length = view.getUint32(0);
      const header = JSON.parse(new TextDecoder().decode(new Uint8Array(data, 4, length)));
      header.image = new Blob([new Uint8Array(data, 4 + length)], {type: 'image/jpeg'});
      this.emit(header.type, header);
      return;
    }
    const message = JSON.parse(data);
    if (message.type === 'reply' && this.pending.has(message.id)) {
      this.pending.get(message.id)(message);
      this.pending.delete(message.id);
    }
    this.emit(message.type, message);
  }

  get isOpen() {
    return this.socket !== null && this.socket.readyState === WebSocket.OPEN;
  }

  request(type, fields = {}) {
    if (!this.isOpen) {
      return Promise.resolve({ok: false, message: 'not connected to the simulator'});
    }
    const id = this.nextId++;
    return new Promise((resolve) => {
      this.pending.set(id, resolve);
      this.socket.send(JSON.stringify({type, id, ...fields}));
    });
  }
}
