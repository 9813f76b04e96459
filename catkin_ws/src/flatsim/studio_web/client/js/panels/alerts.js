// The line that says whether the page is connected, and the messages that say
// why something was refused (a model edited in another window, a bad value).

const SHOW_SECONDS = 6;

export function mount(studio) {
  const status = document.getElementById('connection');
  const alerts = document.getElementById('alerts');
  studio.connection.on('open', () => { status.textContent = 'Connected to the simulator'; });
  studio.connection.on('close', (event) => {
    status.textContent = 'Disconnected from the simulator' + (event.reason ? ': ' + event.reason : '') +
      '. Reload the page once it runs again.';
    status.classList.add('lost');
  });
  studio.on('notice', ({message}) => {
    const line = document.createElement('p');
    line.textContent = message;
    alerts.append(line);
    setTimeout(() => line.remove(), SHOW_SECONDS * 1000);
  });
}
