// Gazebo's right-click menu on a model (its ModelRightMenu), with its words: Move To,
// Follow, Edit model, View (Transparent, Wireframe, Collisions), Copy, Paste and Delete.
// Each entry is an action of the studio (moveTo, follow, editModel, modelLook, copy, paste,
// delete); Delete and Paste go to the simulator as the Edit menu's do. Esc (the keymap's)
// closes the menu, or else stops following, as in Gazebo.

const LOOKS = [['transparent', 'Transparent', 'Make model transparent'],
               ['wireframe', 'Wireframe', 'Wireframe mode'],
               ['collisions', 'Collisions', 'Show collision objects']];

function menuList(label) {
  const list = document.createElement('ul');
  list.className = 'context-menu';
  list.setAttribute('role', 'menu');
  list.setAttribute('aria-label', label);
  list.hidden = true;
  document.body.append(list);
  return list;
}

export function mount(studio) {
  const view = studio.view;
  const menu = menuList('Model');
  const viewMenu = menuList('View');
  let target = null;               // the model the menu is for

  studio.addAction('moveTo', (name) => view.moveTo(name));
  studio.addAction('follow', (name) => view.follow(name));
  studio.addAction('modelLook', (name, look) => view.setLook(name, {...view.lookOf(name), ...look}));

  const close = () => {
    menu.hidden = true;
    viewMenu.hidden = true;
    target = null;
  };

  const item = (list, label, title, run, role = 'menuitem') => {
    const element = document.createElement('li');
    element.setAttribute('role', role);
    element.tabIndex = -1;
    element.textContent = label;
    element.title = title;
    const activate = () => {
      const name = target;
      close();
      if (name !== null) run(name, element);
    };
    element.addEventListener('click', activate);
    element.addEventListener('keydown', (event) => {
      if (event.key === 'Enter' || event.key === ' ') {
        event.preventDefault();
        activate();
      }
    });
    list.append(element);
    return element;
  };
  const separator = (list) => {
    const element = document.createElement('li');
    element.setAttribute('role', 'separator');
    list.append(element);
  };

  item(menu, 'Move To', 'Move camera to the selection', (name) => studio.run('moveTo', name));
  item(menu, 'Follow', 'Follow the selection (Esc stops)', (name) => studio.run('follow', name));
  separator(menu);
  const edit = item(menu, 'Edit model', 'Open on Model Editor', (name) => studio.run('editModel', name));
  separator(menu);
  const viewItem = document.createElement('li');
  viewItem.setAttribute('role', 'menuitem');
  viewItem.setAttribute('aria-haspopup', 'menu');
  viewItem.setAttribute('aria-expanded', 'false');
  viewItem.tabIndex = -1;
  viewItem.textContent = 'View';
  viewItem.className = 'submenu';
  menu.append(viewItem);
  const openView = () => {
    const box = viewItem.getBoundingClientRect();
    viewMenu.style.left = box.right + 'px';
    viewMenu.style.top = box.top + 'px';
    viewMenu.hidden = false;
    viewItem.setAttribute('aria-expanded', 'true');
  };
  viewItem.addEventListener('click', openView);
  viewItem.addEventListener('pointerenter', openView);
  viewItem.addEventListener('keydown', (event) => {
    if (event.key === 'Enter' || event.key === ' ' || event.key === 'ArrowRight') {
      event.preventDefault();
      openView();
      viewMenu.firstElementChild.focus();
    }
  });
  const lookItems = LOOKS.map(([key, label, title]) => {
    const element = item(viewMenu, label, title, (name, it) => {
      studio.run('modelLook', name, {[key]: it.getAttribute('aria-checked') !== 'true'});
    }, 'menuitemcheckbox');
    return [key, element];
  });
  separator(menu);
  item(menu, 'Copy', 'Copy the model (Ctrl+C)', () => studio.run('copy'));
  item(menu, 'Paste', 'Paste a copy of it (Ctrl+V)', () => studio.run('paste'));
  separator(menu);
  item(menu, 'Delete', 'Delete a model', () => studio.run('delete'));

  view.addEventListener('modelmenu', ({detail}) => {
    target = detail.name;
    const look = view.lookOf(target);
    for (const [key, element] of lookItems) element.setAttribute('aria-checked', String(look[key]));
    // Gazebo leaves out Edit model while an editor is open.
    edit.hidden = Boolean(studio.editor);
    viewItem.setAttribute('aria-expanded', 'false');
    viewMenu.hidden = true;
    menu.hidden = false;
    const width = menu.offsetWidth;
    const height = menu.offsetHeight;
    menu.style.left = Math.min(detail.x, window.innerWidth - width - 4) + 'px';
    menu.style.top = Math.min(detail.y, window.innerHeight - height - 4) + 'px';
    menu.firstElementChild.focus();
  });

  document.addEventListener('pointerdown', (event) => {
    if (!menu.hidden && !menu.contains(event.target) && !viewMenu.contains(event.target)) close();
  }, true);
  // Esc (the keymap's, in the world): closes the menu, and then does nothing else; with no
  // menu open, stops following (and the selection mode comes back, as Esc does).
  studio.on('escape', (request) => {
    if (!menu.hidden) {
      close();
      request.handled = true;
    } else if (view.followed) {
      studio.run('follow', null);
    }
  });
  // The menu opens over the Model Editor too (without Edit model): Esc closes it there.
  studio.addAction('closeModelMenu', close, {mode: 'model', keys: ['Esc']});
}
