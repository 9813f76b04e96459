// Editing models in the 3D view as in Gazebo's window: the selection,
// translation, rotation and scale modes (Esc, t, r, s), drags with the handles, Delete,
// and copy/paste (Ctrl+C, Ctrl+V). A drag takes the model's edit lease, so
// that a second window editing it is told so instead of fighting; every
// change goes to the simulator, which streams the result back.

// Poses sent while dragging, at most this many a second.
const DRAG_RATE = 30;
// A drag renews its model's edit lease this often (the simulator's lapses after 2 s).
const LEASE_RENEW_MS = 500;

export function mount(studio) {
  const view = studio.view;
  let copied = null;
  let drag = null;                 // the drag going on: its model, pose to send, lease

  // Gazebo's Scale tool works on simple shapes only; here it says so rather than show nothing.
  const sayWhatScales = () => {
    const name = studio.selected;
    const model = name && view.models.get(name);
    if (view.mode === 'scale' && model && !model.description.simple_shape) {
      studio.inform(name + ' is not a simple shape: the Scale tool scales a box, a cylinder or a sphere');
    }
  };

  const setMode = (mode) => {
    view.setMode(mode);
    studio.emit('mode', {mode});
    sayWhatScales();
  };
  studio.addAction('setMode', setMode, {mode: 'world'});
  studio.on('selection', sayWhatScales);
  // Gazebo's hotkeys for the four modes.
  studio.addAction('translationMode', () => setMode('translate'), {mode: 'world', keys: ['t']});
  studio.addAction('rotationMode', () => setMode('rotate'), {mode: 'world', keys: ['r']});
  studio.addAction('scale', () => setMode('scale'), {mode: 'world', keys: ['s']});
  // Gazebo's Esc in the world: what the page has open for it first (the model menu, which
  // says so by marking the request handled: then that is all Esc does; following a model
  // stops and Esc goes on), else the selection mode.
  studio.addAction('selectionMode', () => {
    const request = {handled: false};
    studio.emit('escape', request);
    if (!request.handled) setMode('select');
  }, {mode: 'world', keys: ['Esc']});

  view.addEventListener('scaled', async ({detail}) => {
    const reply = await studio.request('scale', {model: detail.name, scale: detail.scale});
    studio.connection.request('release', {model: detail.name});
    if (!reply.ok) view.unscale(detail.name);
  });

  studio.addAction('copy', () => {
    if (!studio.selected) return studio.notify('Select a model to copy first');
    copied = studio.selected;
    studio.emit('copied', {name: copied});
  }, {mode: 'world', keys: ['Ctrl+C']});

  studio.addAction('paste', async () => {
    if (!copied) return studio.notify('Copy a model first (select it, then Ctrl+C)');
    const reply = await studio.request('paste', {model: copied});
    if (reply.ok) {
      const selectWhenThere = () => {
        if (view.models.has(reply.name)) view.select(reply.name);
        else setTimeout(selectWhenThere, 50);
      };
      selectWhenThere();
    }
  }, {mode: 'world', keys: ['Ctrl+V']});

  studio.addAction('delete', async () => {
    const name = studio.selected;
    if (!name) return studio.notify('Select a model to delete first');
    await studio.request('delete', {model: name});
  }, {mode: 'world', keys: ['Delete']});

  // The time panel's Reset stays under an editor, and so do its keys (Ctrl+R is never the
  // browser's reload, which would lose a design).
  studio.addAction('resetModelPoses', () => studio.request('reset_model_poses'), {keys: ['Ctrl+Shift+R']});
  studio.addAction('resetWorld', () => studio.request('reset_world'), {keys: ['Ctrl+R']});

  // -- drags --------------------------------------------------------------------------
  // Sends the drag's latest pose, at most DRAG_RATE a second and one at a time;
  // once the drag has ended and its last pose is in, releases the lease.
  const sendPose = async (current) => {
    if (current.refused || current.inFlight) return;
    if (!current.pending) {
      if (current.finished && !current.released) {
        current.released = true;
        studio.connection.request('release', {model: current.name});
      }
      return;
    }
    const wait = current.finished ? 0 : 1000 / DRAG_RATE - (performance.now() - current.lastSent);
    if (wait > 0) {
      if (!current.timer) {
        current.timer = setTimeout(() => { current.timer = null; sendPose(current); }, wait);
      }
      return;
    }
    const pose = current.pending;
    current.pending = null;
    current.inFlight = true;
    current.lastSent = performance.now();
    const reply = await studio.connection.request('set_pose', {model: current.name, pose});
    current.inFlight = false;
    if (!reply.ok && !current.warned) {
      current.warned = true;
      studio.notify(reply.message);
    }
    sendPose(current);
  };

  view.addEventListener('dragstart', async ({detail}) => {
    const current = {name: detail.name, refused: false, inFlight: false, pending: null,
                     lastSent: 0, warned: false, finished: false, released: false, timer: null,
                     renew: null};
    drag = current;
    const reply = await studio.connection.request('lease', {model: detail.name});
    if (reply.ok && !current.finished) {
      // Held while the mouse is, even when it rests: the simulator lets a silent lease lapse.
      current.renew = setInterval(() => {
        if (current.finished) clearInterval(current.renew);
        else studio.connection.request('lease', {model: current.name});
      }, LEASE_RENEW_MS);
    }
    if (!reply.ok) {
      current.refused = true;
      studio.notify(reply.message);
      view.cancelDrag();
      view.applyPoses({[detail.name]: studio.poses[detail.name]}, {});
    }
  });

  view.addEventListener('drag', ({detail}) => {
    if (!drag || drag.refused || drag.name !== detail.name) return;
    drag.pending = detail.pose;
    sendPose(drag);
  });

  view.addEventListener('dragend', ({detail}) => {
    if (!drag || drag.name !== detail.name) return;
    const current = drag;
    drag = null;
    if (current.refused) return;
    current.finished = true;
    clearInterval(current.renew);
    if (detail.pose) current.pending = detail.pose;
    sendPose(current);
  });
}
