// gzclient's time panel: play/pause, step, and the real-time factor, sim
// time, real time and iterations, with its Reset button (Reset World).

function clock(seconds) {
  const whole = Math.floor(seconds);
  const hours = Math.floor(whole / 3600);
  const minutes = Math.floor((whole % 3600) / 60);
  const rest = (seconds - hours * 3600 - minutes * 60).toFixed(3).padStart(6, '0');
  return String(hours).padStart(2, '0') + ':' + String(minutes).padStart(2, '0') + ':' + rest;
}

export function mount(studio) {
  const bar = document.querySelector('.time-panel');
  const play = document.createElement('button');
  play.textContent = 'Pause';
  play.addEventListener('click', () => {
    const paused = studio.status && studio.status.paused;
    studio.request(paused ? 'play' : 'pause');
  });
  const step = document.createElement('button');
  step.textContent = 'Step';
  step.title = 'Advance the paused world by the given number of steps';
  const stepsLabel = document.createElement('label');
  stepsLabel.textContent = 'steps ';
  const steps = document.createElement('input');
  steps.type = 'number';
  steps.min = '1';
  steps.max = '1000';          // the server's MAX_STEPS (flatsim.studio.protocol)
  steps.value = '1';
  steps.setAttribute('aria-label', 'steps');
  stepsLabel.append(steps);
  step.addEventListener('click', () => studio.request('step', {count: Math.max(1, Math.round(Number(steps.value)) || 1)}));
  bar.append(play, step, stepsLabel);
  const outputs = {};
  for (const [key, label] of [['real_time_factor', 'Real Time Factor:'], ['sim_time', 'Sim Time:'],
                              ['real_time', 'Real Time:'], ['iterations', 'Iterations:']]) {
    const wrapper = document.createElement('span');
    const name = document.createElement('label');
    name.textContent = label + ' ';
    const output = document.createElement('output');
    output.id = 'time-' + key;
    output.setAttribute('aria-label', label.replace(':', ''));
    name.htmlFor = output.id;
    wrapper.append(name, output);
    bar.append(wrapper);
    outputs[key] = output;
  }
  const reset = document.createElement('button');
  reset.textContent = 'Reset';
  reset.title = 'Reset World: models back to their start, time back to zero';
  reset.addEventListener('click', () => studio.run('resetWorld'));
  bar.append(reset);

  studio.on('status', (status) => {
    play.textContent = status.paused ? 'Play' : 'Pause';
    step.disabled = !status.paused;
    outputs.real_time_factor.value = status.real_time_factor.toFixed(2);
    outputs.sim_time.value = clock(status.sim_time);
    outputs.real_time.value = clock(status.real_time);
    outputs.iterations.value = String(status.iterations);
    bar.dataset.simTime = String(status.sim_time);
  });
}
