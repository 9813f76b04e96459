// What flatsim left out of the world and the robots (meshes it cannot read,
// plugins it does not run, models it holds still), as the simulator lists it.

import {namedList} from './elements.js';

export function mount(studio) {
  const section = document.createElement('section');
  section.setAttribute('aria-labelledby', 'skipped-heading');
  const [heading, list] = namedList('skipped-heading', 'Skipped by flatsim', 'skipped');
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
