// The menu bar, with Gazebo's menus and words. Panels add entries with
// studio.menus.add(menu, {label, action, shortcut}) or .addCheck(menu, {label, onChange});
// an editor makes a bar of its own with new Menus(element), as Gazebo's editors swap menu bars.

function closeAll(bar) {
  for (const button of bar.querySelectorAll('.menu > button')) {
    button.setAttribute('aria-expanded', 'false');
    button.nextElementSibling.hidden = true;
  }
}

export class Menus {
  constructor(bar) {
    this.bar = bar;
    this.menus = new Map();
    document.addEventListener('click', (event) => {
      if (!bar.contains(event.target)) closeAll(bar);
    });
  }

  menu(name) {
    if (this.menus.has(name)) return this.menus.get(name);
    const wrapper = document.createElement('div');
    wrapper.className = 'menu';
    const button = document.createElement('button');
    button.textContent = name;
    button.setAttribute('aria-haspopup', 'menu');
    button.setAttribute('aria-expanded', 'false');
    const list = document.createElement('ul');
    list.setAttribute('role', 'menu');
    list.setAttribute('aria-label', name);
    list.hidden = true;
    button.addEventListener('click', () => {
      const open = button.getAttribute('aria-expanded') === 'true';
      closeAll(this.bar);
      button.setAttribute('aria-expanded', String(!open));
      list.hidden = open;
      if (!open && list.firstElementChild) list.firstElementChild.focus();
    });
    wrapper.append(button, list);
    this.bar.append(wrapper);
    this.menus.set(name, list);
    return list;
  }

  item(menuName, role, label, shortcut, onActivate) {
    const list = this.menu(menuName);
    const item = document.createElement('li');
    item.setAttribute('role', role);
    item.tabIndex = -1;
    item.textContent = label;
    if (shortcut) {
      const hint = document.createElement('span');
      hint.className = 'shortcut';
      hint.setAttribute('aria-hidden', 'true');
      hint.textContent = shortcut;
      item.append(hint);
      item.setAttribute('aria-keyshortcuts', shortcut);
    }
    const activate = () => {
      closeAll(this.bar);
      onActivate(item);
    };
    item.addEventListener('click', activate);
    item.addEventListener('keydown', (event) => {
      if (event.key === 'Enter' || event.key === ' ') { event.preventDefault(); activate(); }
    });
    list.append(item);
    return item;
  }

  add(menuName, {label, action, shortcut}) {
    return this.item(menuName, 'menuitem', label, shortcut, () => action());
  }

  addCheck(menuName, {label, checked = false, onChange}) {
    const item = this.item(menuName, 'menuitemcheckbox', label, null, (it) => {
      const now = it.getAttribute('aria-checked') !== 'true';
      it.setAttribute('aria-checked', String(now));
      onChange(now);
    });
    item.setAttribute('aria-checked', String(checked));
    return item;
  }
}

export function mount(studio) {
  // The studio made the window's menu bar (studio.menus), in Gazebo's order of menus.
  const menus = studio.menus;
  // Gazebo's Edit menu, less the editors (they mount their own entries).
  menus.add('Edit', {label: 'Reset Model Poses', shortcut: 'Ctrl+Shift+R',
                     action: () => studio.run('resetModelPoses')});
  menus.add('Edit', {label: 'Reset World', shortcut: 'Ctrl+R', action: () => studio.run('resetWorld')});
  menus.add('Edit', {label: 'Copy', shortcut: 'Ctrl+C', action: () => studio.run('copy')});
  menus.add('Edit', {label: 'Paste', shortcut: 'Ctrl+V', action: () => studio.run('paste')});
  menus.add('Edit', {label: 'Delete', shortcut: 'Delete', action: () => studio.run('delete')});
  menus.add('Camera', {label: 'Reset View', action: () => studio.view.frameAll()});
}
