// The robot camera's image, as the simulator renders it, only while the panel
// is open (Window > Camera): closed, the simulator renders nothing for it.

export function mount(studio) {
  const panel = document.createElement('section');
  panel.className = 'camera-panel';
  panel.setAttribute('aria-labelledby', 'camera-heading');
  panel.hidden = true;
  const heading = document.createElement('h2');
  heading.id = 'camera-heading';
  heading.textContent = 'Camera';
  const choice = document.createElement('select');
  choice.setAttribute('aria-label', 'camera');
  const image = document.createElement('img');
  image.alt = 'no camera image yet';
  panel.append(heading, choice, image);
  document.querySelector('.right').append(panel);
  let url = null;

  const want = (on) => {
    const sensor = choice.value;
    if (on && !sensor) {
      studio.notify('The world has no camera');
      return;
    }
    studio.request('camera', on ? {sensor, on: true} : {on: false});
  };

  studio.on('scene', (scene) => {
    const cameras = [];
    for (const model of scene.models) {
      for (const sensor of model.sensors) {
        if (sensor.kind === 'camera') cameras.push(model.name + '::' + sensor.name);
      }
    }
    const previous = choice.value;
    choice.replaceChildren(...cameras.map((name) => new Option(name, name)));
    if (cameras.includes(previous)) choice.value = previous;
    if (!panel.hidden) want(cameras.length > 0);
  });
  choice.addEventListener('change', () => want(true));
  studio.connection.on('camera_image', (frame) => {
    if (panel.hidden || frame.sensor !== choice.value) return;
    if (url) URL.revokeObjectURL(url);
    url = URL.createObjectURL(frame.image);
    image.src = url;
    image.alt = 'camera image of ' + frame.sensor + ' at sim time ' + frame.sim_time.toFixed(2) + ' s';
  });
  studio.cameraPanel = {
    setOpen(open) {
      panel.hidden = !open;
      want(open);
    },
  };
  studio.menus.addCheck('Window', {label: 'Camera', onChange: (open) => studio.cameraPanel.setOpen(open)});
}
