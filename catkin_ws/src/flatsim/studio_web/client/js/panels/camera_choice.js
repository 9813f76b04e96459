// A panel's camera: the list of the world's cameras, kept as scenes come, and the stream the
// panel asks the simulator for (the Camera panel's 'camera', the Chase view's 'chase'), only
// while the panel is open.

export function followCameras(studio, panel, choice, command) {
  const want = (on) => {
    const sensor = choice.value;
    if (on && !sensor) {
      studio.notify('The world has no camera');
      return;
    }
    studio.request(command, on ? {sensor, on: true} : {on: false});
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
  return want;
}
