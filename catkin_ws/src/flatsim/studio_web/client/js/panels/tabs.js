// The left panel's tabs (Gazebo's World, and Insert when its panel mounts):
// studio.addTab(name) returns the tab's panel element.

export function mount(studio) {
  const list = document.querySelector('.left .tabs');
  const panels = document.querySelector('.left .tab-panels');
  const tabs = [];
  const show = (chosen) => {
    for (const {tab, panel} of tabs) {
      const selected = tab === chosen;
      tab.setAttribute('aria-selected', String(selected));
      tab.tabIndex = selected ? 0 : -1;
      panel.hidden = !selected;
    }
  };
  studio.addTab = (name) => {
    const id = 'tab-' + name.toLowerCase().replace(/\W+/g, '-');
    const tab = document.createElement('button');
    tab.setAttribute('role', 'tab');
    tab.id = id;
    tab.textContent = name;
    const panel = document.createElement('div');
    panel.setAttribute('role', 'tabpanel');
    panel.setAttribute('aria-labelledby', id);
    list.append(tab);
    panels.append(panel);
    tabs.push({tab, panel});
    tab.addEventListener('click', () => show(tab));
    show(tabs[0].tab);
    return panel;
  };
}
