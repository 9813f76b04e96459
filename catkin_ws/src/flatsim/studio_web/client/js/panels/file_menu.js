// Gazebo's File menu: Save World (Ctrl+S) writes over the world's file (the WORLD of
// `gazebo WORLD`, or the last Save World As), and Save World As (Ctrl+Shift+S) asks for a
// folder and a file name (one ending in .world), and asks before replacing a file that is
// there. The page then says where it saved and what it left out (the
// robot a launch file spawned). While an editor is open, Ctrl+S and Ctrl+Shift+S are its own
// (editor_shell.js binds them in its mode).

import {ask, chooseFolder, labelledInput, makeButton} from './dialogs.js';

export function mount(studio) {
  let lastFolder = null;

  const report = (reply) => {
    if (!reply.ok) return false;
    studio.inform('Saved the world in ' + reply.path);
    for (const note of reply.notes) studio.inform(note);
    return true;
  };

  // A file that is there already is replaced only once the user says so, as Gazebo's dialog asks.
  const saveAs = async (folder, file) => {
    const reply = await studio.request('save_world', {folder, file});
    if (!reply.ok || reply.saved) return report(reply);
    const replace = await ask({title: 'Replace File', text: reply.message, buttons: [
      {label: 'Cancel', value: null}, {label: 'Replace', value: true, primary: true}]});
    return replace ? report(await studio.request('save_world', {folder, file, overwrite: true})) : false;
  };

  const saveWorldAs = async () => {
    const places = await studio.request('places');
    if (!places.ok) return false;
    const file = places.world_file;
    let folder = lastFolder || (file ? file.slice(0, file.lastIndexOf('/')) : '');
    const [whereLabel, where] = labelledInput('Location:', {value: folder});
    where.readOnly = true;
    where.placeholder = 'Browse to choose a folder';
    const browse = makeButton('Browse', async () => {
      const chosen = await chooseFolder(studio, folder || places.home);
      if (chosen) where.value = folder = chosen;
    });
    const fileName = file ? file.slice(file.lastIndexOf('/') + 1) : '';
    const [nameLabel, name] = labelledInput('File name:', {value: fileName});
    const grid = document.createElement('div');
    grid.className = 'form';
    grid.append(whereLabel, where, document.createElement('span'), browse, nameLabel, name);
    const pressed = await ask({
      title: 'Save World', body: [grid],
      buttons: [{label: 'Cancel', value: null}, {label: 'Save', value: 'save', primary: true}],
      check: async () => {
        if (!folder) studio.notify('Choose the folder to save in with Browse');
        else if (!name.value.trim()) studio.notify('Give the world file a name, such as myworld.world');
        else return saveAs(folder, name.value.trim());
        return false;
      },
    });
    if (pressed === 'save') lastFolder = folder;
    return pressed === 'save';
  };

  const saveWorld = async () => {
    const places = await studio.request('places');
    if (!places.ok) return false;
    if (!places.world_file) return saveWorldAs();
    return report(await studio.request('save_world'));
  };

  studio.addAction('saveWorld', saveWorld, {mode: 'world', keys: ['Ctrl+S']});
  studio.addAction('saveWorldAs', saveWorldAs, {mode: 'world', keys: ['Ctrl+Shift+S']});
  studio.menus.add('File', {label: 'Save World', shortcut: 'Ctrl+S', action: saveWorld});
  studio.menus.add('File', {label: 'Save World As', shortcut: 'Ctrl+Shift+S', action: saveWorldAs});
}
