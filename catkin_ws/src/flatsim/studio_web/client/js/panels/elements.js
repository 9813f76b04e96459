// Small builders the panels share, so that every list a test looks for has a name.

// An <h2> and the list it names: [heading, list].
export function namedList(id, title, className) {
  const heading = document.createElement('h2');
  heading.id = id;
  heading.textContent = title;
  const list = document.createElement('ul');
  list.className = className;
  list.setAttribute('aria-labelledby', id);
  return [heading, list];
}
