// The left panel's tabs (Gazebo's World, and Insert when its panel mounts):
// studio.addTab(name) returns the tab's panel element.

export class Tabs {
  constructor(list, panels) {
    this.list = list;
    this.panels = panels;
    this.tabs = [];
  }

  show(chosen) {
    for (const {tab, panel} of this.tabs) {
      const selected = tab === chosen;
      tab.setAttribute('aria-selected', String(selected));
      tab.tabIndex = selected ? 0 : -1;
      panel.hidden = !selected;
    }
  }

  add(name) {
    const id = 'tab-' + name.toLowerCase().replace(/\W+/g, '-');
    const tab = document.createElement('button');
    tab.setAttribute('role', 'tab');
    tab.id = id;
    tab.textContent = name;
    const panel = document.createElement('div');
    panel.setAttribute('role', 'tabpanel');
    panel.setAttribute('aria-labelledby', id);
    this.list.append(tab);
    this.panels.append(panel);
    this.tabs.push({tab, panel});
    tab.addEventListener('click', () => this.show(tab));
    this.show(this.tabs[0].tab);
    return panel;
  }
}
