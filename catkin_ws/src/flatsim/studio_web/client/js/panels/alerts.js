// The line that says whether the page is connected, the alerts that say why
// something was refused (a model edited in another window, a bad value), and the
// messages that say what was done (a world saved, and what it left out).
// Alerts and messages stack in one column at the top right of the view, the newest
// alerts first; clicks go through them to the view (a drop, a selection), but for
// each one's Dismiss button. A few of each are shown at once, the oldest going first.

const ALERT_SECONDS = 6;
const INFO_SECONDS = 8;
const MAX_ALERTS = 3;
const MAX_MESSAGES = 4;

export function mount(studio) {
  const status = document.getElementById('connection');
  const alerts = document.getElementById('alerts');
  const messages = document.getElementById('messages');
  studio.connection.on('open', () => { status.textContent = 'Connected to the simulator'; });
  studio.connection.on('close', (event) => {
    status.textContent = 'Disconnected from the simulator' + (event.reason ? ': ' + event.reason : '') +
      '. Reload the page once it runs again.';
    status.classList.add('lost');
  });
  const stack = document.createElement('div');
  stack.className = 'notice-stack';
  alerts.before(stack);
  stack.append(alerts, messages);
  studio.on('notice', ({message, kind}) => {
    const info = kind === 'info';
    const where = info ? messages : alerts;
    const line = document.createElement('p');
    const text = document.createElement('span');
    text.textContent = message;
    const dismiss = document.createElement('button');
    dismiss.type = 'button';
    dismiss.className = 'dismiss';
    dismiss.textContent = '\u00d7';
    dismiss.title = 'Dismiss';
    dismiss.setAttribute('aria-label', 'Dismiss');
    dismiss.addEventListener('click', () => line.remove());
    line.append(text, dismiss);
    where.append(line);
    while (where.children.length > (info ? MAX_MESSAGES : MAX_ALERTS)) where.firstElementChild.remove();
    setTimeout(() => line.remove(), (info ? INFO_SECONDS : ALERT_SECONDS) * 1000);
  });
}
