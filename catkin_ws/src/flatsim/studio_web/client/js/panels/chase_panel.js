// Window > Chase: what a ball chaser's process_image works with, from the robot's camera.
// The simulator counts the pixels that are exactly (255, 255, 255) in each third of the
// image (flatsim.studio.chase) and paints them; the strip under it shows the /cmd_vel
// commands of the last 10 s of sim time and, as marks on the same timeline, the lines that the
// node serving /ball_chaser/command_robot logged (flatsim.studio.service_watch): a service call
// is seen by no other node, so its request and answer show only as that node logs them.
// Closed, the simulator does nothing for it.

import {followCameras} from './camera_choice.js';

const THIRDS = ['left', 'middle', 'right'];
const SHOWN_COMMANDS = 6;
const SHOWN_LINES = 4;
const LINEAR_COLOUR = '#f39c12';
const ANGULAR_COLOUR = '#5dade2';
const LINE_COLOUR = '#c39bd3';
const ERROR_COLOUR = '#e74c3c';

function number(value, digits = 2) {
  return typeof value === 'number' ? value.toFixed(digits) : String(value);
}

function baseName(node) {
  return node.slice(node.lastIndexOf('/') + 1) || node;
}

// What the strip says of the calls when there is no line to list, in plain words.
function callsNote(calls, window) {
  if (!calls.looked_up) return 'looking for the node that serves ' + calls.service + '…';
  if (!calls.server) {
    return 'no node serves ' + calls.service + ': no call to show';
  }
  return baseName(calls.server) + ' (' + calls.server + ') logged no call in the last ' + window +
    ' s — a ROS 1 service call is seen only through what the node that serves it logs';
}

function drawStrip(canvas, frame) {
  const context = canvas.getContext('2d');
  const {width, height} = canvas;
  context.clearRect(0, 0, width, height);
  const start = frame.sim_time - frame.window;
  const x = (t) => ((t - start) / frame.window) * width;
  const finite = frame.commands.flatMap((c) => [c.linear_x, c.angular_z]).filter((v) => typeof v === 'number');
  const scale = Math.max(1, ...finite.map(Math.abs));
  const y = (value) => height / 2 - (value / scale) * (height / 2 - 4);
  context.strokeStyle = '#555';
  context.beginPath();
  context.moveTo(0, height / 2);
  context.lineTo(width, height / 2);
  context.stroke();
  for (const [field, colour] of [['linear_x', LINEAR_COLOUR], ['angular_z', ANGULAR_COLOUR]]) {
    context.strokeStyle = colour;
    context.fillStyle = colour;
    context.beginPath();
    let last = null;
    for (const command of frame.commands) {
      const value = command[field];
      if (typeof value !== 'number') continue;
      // The drive keeps a command until the next one: a step line.
      if (last === null) context.moveTo(x(command.t), y(value));
      else context.lineTo(x(command.t), y(last));
      context.lineTo(x(command.t), y(value));
      last = value;
    }
    if (last !== null) context.lineTo(width, y(last));
    context.stroke();
    for (const command of frame.commands) {
      if (typeof command[field] === 'number') context.fillRect(x(command.t) - 1, y(command[field]) - 1, 3, 3);
    }
  }
  // The serving node's log lines: a triangle each along the top, on the same timeline.
  for (const [t, level] of frame.calls ? frame.calls.marks : []) {
    const at = x(t);
    context.fillStyle = level === 'ERROR' || level === 'FATAL' ? ERROR_COLOUR : LINE_COLOUR;
    context.beginPath();
    context.moveTo(at - 3, 0);
    context.lineTo(at + 3, 0);
    context.lineTo(at, 6);
    context.fill();
  }
  context.fillStyle = '#a9adb3';
  context.fillText('±' + number(scale, 1), 2, 10);
  context.fillText('-' + frame.window + ' s', 2, height - 2);
}

export function mount(studio) {
  const panel = document.createElement('section');
  panel.className = 'chase-panel';
  panel.setAttribute('aria-labelledby', 'chase-heading');
  panel.hidden = true;
  const heading = document.createElement('h2');
  heading.id = 'chase-heading';
  heading.textContent = 'Chase';
  const choice = document.createElement('select');
  choice.setAttribute('aria-label', 'chase camera');
  const picture = document.createElement('div');
  picture.className = 'chase-image';
  const image = document.createElement('img');
  image.alt = 'no chase image yet';
  const lines = [0, 1].map(() => {
    const line = document.createElement('div');
    line.className = 'third-line';
    line.setAttribute('aria-hidden', 'true');
    return line;
  });
  picture.append(image, ...lines);
  const counts = document.createElement('div');
  counts.className = 'chase-counts';
  counts.setAttribute('role', 'group');
  counts.setAttribute('aria-label', 'pixels of (255, 255, 255) per third');
  const outputs = THIRDS.map((third) => {
    const cell = document.createElement('label');
    const output = document.createElement('output');
    output.setAttribute('aria-label', third + ' third');
    output.textContent = '–';
    cell.append(third + ' ', output);
    counts.append(cell);
    return output;
  });
  const stripHeading = document.createElement('h3');
  stripHeading.textContent = '/cmd_vel, last 10 s of sim time';
  const legend = document.createElement('p');
  legend.className = 'chase-legend';
  legend.innerHTML = `<span style="color:${LINEAR_COLOUR}">linear.x (m/s)</span> · ` +
                     `<span style="color:${ANGULAR_COLOUR}">angular.z (rad/s, + turns left)</span> · ` +
                     `<span style="color:${LINE_COLOUR}">▼ a line the service's node logged</span>`;
  const strip = document.createElement('canvas');
  strip.className = 'chase-strip';
  strip.width = 328;
  strip.height = 80;
  strip.setAttribute('role', 'img');
  strip.setAttribute('aria-label', 'linear.x and angular.z over the last 10 s, and the lines the ' +
    'service\'s node logged');
  const list = document.createElement('ol');
  list.className = 'chase-commands';
  list.setAttribute('aria-label', 'commands on /cmd_vel, newest first');
  const callsHeading = document.createElement('h3');
  callsHeading.textContent = 'calls to /ball_chaser/command_robot, as the node that serves it logs them';
  const lineList = document.createElement('ol');
  lineList.className = 'chase-commands chase-calls';
  lineList.setAttribute('aria-label', 'lines the service\'s node logged, newest first');
  const note = document.createElement('p');
  note.className = 'chase-note';
  note.textContent = 'In ROS 1 a service call goes straight from the caller (process_image) to the node ' +
    'that serves it (drive_bot), and no other node sees it: there is no rosservice echo. So the calls ' +
    'show here as that node logs them on /rosout (the request and the answer, if it logs them). While ' +
    'this view is open the simulator raises that node\'s log level to DEBUG, where the project\'s ' +
    'drive_bot logs every call, and puts it back when the view closes. Each call drive_bot answers ' +
    'also publishes one /cmd_vel, listed above with the node that sent it.';
  const callParts = [callsHeading, lineList, note];
  panel.append(heading, choice, picture, counts, stripHeading, legend, strip, list, ...callParts);
  document.querySelector('.right').append(panel);
  let url = null;

  const want = followCameras(studio, panel, choice, 'chase');
  studio.connection.on('chase_image', (frame) => {
    if (panel.hidden || frame.sensor !== choice.value) return;
    if (url) URL.revokeObjectURL(url);
    url = URL.createObjectURL(frame.image);
    image.src = url;
    image.alt = 'chase view of ' + frame.sensor + ' at sim time ' + frame.sim_time.toFixed(2) + ' s';
    frame.thirds.forEach((column, index) => {
      lines[index].style.left = (100 * column / frame.image_width) + '%';
    });
    frame.counts.forEach((count, index) => { outputs[index].textContent = String(count); });
    panel.dataset.simTime = String(frame.sim_time);
    drawStrip(strip, frame);
    const newest = frame.commands.slice(-SHOWN_COMMANDS).reverse();
    list.replaceChildren(...newest.map((command) => {
      const item = document.createElement('li');
      item.textContent = number(command.t) + ' s  linear.x ' + number(command.linear_x) +
        '  angular.z ' + number(command.angular_z) + '  from ' + (command.sender || 'an unknown node') +
        (command.refused ? '  refused: ' + command.refused : '');
      if (command.refused) item.className = 'refused';
      return item;
    }));
    if (!newest.length) {
      const item = document.createElement('li');
      item.className = 'none';
      item.textContent = 'no /cmd_vel in the last ' + frame.window + ' s';
      list.append(item);
    }
    const calls = frame.calls;
    for (const part of callParts) part.hidden = !calls;
    if (!calls) return;
    const logged = calls.lines.slice(-SHOWN_LINES).reverse();
    lineList.replaceChildren(...logged.map((line) => {
      const item = document.createElement('li');
      // textContent: a node's log text is shown as text, whatever it holds.
      item.textContent = number(line.t) + ' s  ' + line.node + '  ' + line.text;
      if (line.level === 'ERROR' || line.level === 'FATAL') item.className = 'refused';
      return item;
    }));
    if (!logged.length) {
      const item = document.createElement('li');
      item.className = 'none';
      item.textContent = callsNote(calls, frame.window);
      lineList.append(item);
    }
  });
  studio.chasePanel = {
    setOpen(open) {
      panel.hidden = !open;
      want(open);
    },
  };
  studio.menus.addCheck('Window', {label: 'Chase', onChange: (open) => studio.chasePanel.setOpen(open)});
}
