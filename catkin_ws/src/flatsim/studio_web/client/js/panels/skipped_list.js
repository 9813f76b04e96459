// What flatsim left out of the world and the robots (meshes it cannot read,
// plugins it does not run, models it holds still), as the simulator lists it.

export function mount(studio) {
  const section = document.createElement('section');
  section.setAttribute('aria-labelledby', 'skipped-heading');
  const heading = document.createElement('h2');
  heading.id = 'skipped-heading';
  heading.textContent = 'Skipped by flatsim';
  const list = document.createElement('ul');
  list.className = 'skipped';
  list.setAttribute('aria-labelledby', heading.id);
  section.append(heading, list);
  document.querySelector('.left').append(section);
  studio.on('skipped', ({items}) => {
    list.replaceChildren(...items.map(({subject, reason}) => {
      const item = document.createElement('li');
      item.textContent = subject + ': ' + reason;
      return item;
    }));
    heading.textContent = 'Skipped by flatsim (' + items.length + ')';
  });
}
