// The line that says whether the page is connected, the alerts that say why
// something was refused (a model edited in another window, a bad value), and the
// messages that say what was done (a world saved, and what it left out).

const SHOW_SECONDS = 6;
const INFO_SECONDS = 15;

export function mount(studio) {
  const status = document.getElementById('connection');
  const alerts = document.getElementById('alerts');
  studio.connection.on('open', () => { status.textContent = 'Connected to the simulator'; });
  studio.connection.on('close', (event) => {
    status.textContent = 'Disconnected from the simulator' + (event.reason ? ': ' + event.reason : '') +
      '. Reload the page once it runs again.';
    status.classList.add('lost');
  });
  const messages = document.getElementById('messages');
  studio.on('notice', ({message, kind}) => {
    const line = document.createElement('p');
    line.textContent = message;
    (kind === 'info' ? messages : alerts).append(line);
    setTimeout(() => line.remove(), (kind === 'info' ? INFO_SECONDS : SHOW_SECONDS) * 1000);
  });
}
