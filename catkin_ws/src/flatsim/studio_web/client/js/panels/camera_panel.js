// The robot camera's image, as the simulator renders it, only while the panel
// is open (Window > Camera): closed, the simulator renders nothing for it.

import {followCameras} from './camera_choice.js';

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

  const want = followCameras(studio, panel, choice, 'camera');
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
