// View menu: what the sensors see, drawn into the 3D view on request: the
// lidars' rays (sent only while shown) and the cameras' fields of view.

export function mount(studio) {
  let scansOn = false;
  studio.connection.on('scans', ({scans}) => { if (scansOn) studio.view.setScans(scans); });
  studio.menus.addCheck('View', {label: 'Lidar Rays', onChange: (on) => {
    scansOn = on;
    studio.request('scans', {on});
    if (!on) studio.view.setScans(null);
  }});
  studio.menus.addCheck('View', {label: 'Camera Field of View',
                                 onChange: (on) => studio.view.setConesVisible(on)});
}
