// mresim viewer page: talks to the server over one WebSocket (mresim_phys/viewer/protocol.py).
// Frames arrive as a JSON header followed by one binary PNG, drawn unscaled on #frame.
"use strict";

const $ = (id) => document.getElementById(id);
const state = {
  info: null, layers: null, n: 0, target: 0, step: 0, playing: false, finished: false,
  speed: 10, inflight: false, dirty: false, header: null, agents: [], frames: 0,
  timeline: { steps: [], explored: [], known_at_base: [], events: [] },
  lastAdvance: 0, timer: null, socket: null,
  view: { zoom: 1, x: 0, y: 0 }, drag: null,
};
window.viewer = state; // for tests and the curious

function connect() {
  const proto = location.protocol === "https:" ? "wss:" : "ws:";
  const ws = new WebSocket(`${proto}//${location.host}/ws`);
  ws.binaryType = "blob";
  ws.onmessage = (ev) => (typeof ev.data === "string" ? onJson(JSON.parse(ev.data)) : onPng(ev.data));
  ws.onclose = () => { $("status").textContent = "disconnected"; };
  state.socket = ws;
}

function send(msg) {
  if (state.socket && state.socket.readyState === WebSocket.OPEN) state.socket.send(JSON.stringify(msg));
}

function live() { return state.info && state.info.mode === "live" && !state.finished; }

function onJson(msg) {
  if (msg.type === "info") return onInfo(msg);
  if (msg.type === "frame") { state.header = msg; return; }
  if (msg.type === "reload") { state.socket.onclose = null; state.socket.close(); state.finished = false; connect(); return; }
  if (msg.type === "error") { console.warn("viewer server:", msg.message); $("status").textContent = msg.message; }
}

function onInfo(info) {
  const same = state.info && JSON.stringify(state.info.names) === JSON.stringify(info.names);
  state.info = info;
  if (!same) state.layers = info.layers;
  state.timeline = { steps: [], explored: [], known_at_base: [], events: [] };
  mergeTimeline(info.timeline);
  const canvas = $("frame");
  canvas.width = info.size[0]; canvas.height = info.size[1];
  $("title").textContent = `${info.name} seed ${info.seed}`;
  $("mode").textContent = info.mode;
  $("stop").hidden = info.mode !== "live";
  state.playing = false; state.inflight = false;
  if (info.mode === "live") { $("speed").value = "0"; state.speed = 0; }
  if (info.mode === "replay") { state.target = Math.min(state.n, info.steps - 1); }
  buildPanel();
  updateControls();
  requestFrame();
}

function mergeTimeline(t) {
  const tl = state.timeline;
  if (!t || t.start !== tl.steps.length) return;
  tl.steps.push(...t.steps); tl.explored.push(...t.explored); tl.known_at_base.push(...t.known_at_base);
  tl.events.push(...t.events);
  if (t.events.length || t.steps.length) drawMarks();
}

async function onPng(blob) {
  const header = state.header;
  const bitmap = await createImageBitmap(blob, { colorSpaceConversion: "none", premultiplyAlpha: "none" });
  const ctx = $("frame").getContext("2d");
  ctx.drawImage(bitmap, 0, 0);
  bitmap.close();
  state.frames += 1;
  state.n = header.n; state.step = header.step; state.agents = header.agents;
  mergeTimeline(header.timeline);
  if (state.info.mode === "live") { state.playing = header.playing; state.finished = header.finished; }
  $("step").textContent = header.step;
  $("status").textContent = header.events.length ? header.events.join(", ") : "";
  state.inflight = false;
  updateControls();
  updateStatus();
  drawChart();
  if (state.dirty) { state.dirty = false; requestFrame(); return; }
  if (live() && state.playing) { schedule(50); return; }
  if (!live() && state.playing) playOn();
}

function schedule(ms) {
  clearTimeout(state.timer);
  state.timer = setTimeout(requestFrame, ms);
}

function requestFrame() {
  if (!state.info) return;
  if (state.inflight) { state.dirty = true; return; }
  state.inflight = true;
  send({ op: "frame", n: state.target, layers: state.layers, known: state.timeline.steps.length });
}

function seek(n) {
  if (!state.info || live()) return;
  state.target = Math.max(0, Math.min(n, state.info.steps - 1));
  requestFrame();
}

function playOn() {
  const last = state.info.steps - 1;
  if (state.n >= last) { setPlaying(false); return; }
  const speed = state.speed > 0 ? state.speed : 1000;
  const interval = 1000 / Math.min(speed, 25);
  const wait = Math.max(0, state.lastAdvance + interval - performance.now());
  clearTimeout(state.timer);
  state.timer = setTimeout(() => {
    if (!state.playing) return;
    const now = performance.now();
    const gone = state.lastAdvance ? (now - state.lastAdvance) / 1000 : 1 / speed;
    state.lastAdvance = now;
    seek(state.n + Math.max(1, Math.round(speed * gone)));
  }, wait);
}

function setPlaying(on) {
  if (live()) { send({ op: on ? "play" : "pause" }); state.playing = on; if (on) schedule(0); updateControls(); return; }
  state.playing = on && state.info && state.n < state.info.steps - 1;
  state.lastAdvance = 0;
  updateControls();
  if (state.playing) playOn();
}

function stepBy(delta) {
  if (!state.info) return;
  if (live()) {
    if (delta > 0) { send({ op: "step" }); state.playing = false; setTimeout(requestFrame, 30); }
    return;
  }
  setPlaying(false);
  seek(state.n + delta);
}

function updateControls() {
  const info = state.info;
  if (!info) return;
  $("play").innerHTML = state.playing ? "&#x23F8;" : "&#x25B6;";
  $("play").title = state.playing ? "pause (space)" : "play (space)";
  const scrub = $("scrub");
  const total = live() ? info.steps : info.steps;
  scrub.max = String(Math.max(total - 1, 0));
  scrub.value = String(state.n);
  scrub.disabled = live();
  $("back").disabled = live();
  $("stop").disabled = !live();
}

function toggle(list, name, on) {
  const i = list.indexOf(name);
  if (on && i < 0) list.push(name);
  if (!on && i >= 0) list.splice(i, 1);
}

function checkbox(id, checked, onChange, title) {
  const box = document.createElement("input");
  box.type = "checkbox"; box.id = id; box.checked = checked; box.title = title;
  box.addEventListener("change", () => { onChange(box.checked); requestFrame(); syncPanel(); });
  return box;
}

function buildPanel() {
  const info = state.info, layers = state.layers;
  const team = $("team");
  team.replaceChildren();
  for (const name of info.global_layers) {
    const label = document.createElement("label");
    label.append(checkbox(`team-${name}`, layers.team.includes(name), (on) => toggle(layers.team, name, on), name), " " + name);
    team.append(label);
  }
  const table = $("robots");
  table.replaceChildren();
  const head = table.insertRow();
  head.insertCell().textContent = "";
  info.robot_layers.forEach((name, k) => {
    const th = document.createElement("th");
    th.textContent = k < 10 ? `${(k + 1) % 10} ${name}` : name;
    head.append(th);
  });
  const status = document.createElement("th");
  status.textContent = "status";
  head.append(status);
  const rows = [["*", "all robots"], ...info.names.map((n) => [n, n])];
  for (const [agent, label] of rows) {
    const row = table.insertRow();
    const cell = row.insertCell(); cell.className = "name"; cell.textContent = label;
    const k = info.names.indexOf(agent);
    if (k >= 0 && info.colours) cell.style.borderLeftColor = info.colours[k];
    for (const name of info.robot_layers) {
      const td = row.insertCell();
      const on = agent === "*" ? allHave(name) : layers.robots[agent].includes(name);
      const id = agent === "*" ? `all-${name}` : `layer-${agent}-${name}`;
      td.append(checkbox(id, on, (v) => setRobotLayer(agent, name, v), `${label}: ${name}`));
    }
    const mark = row.insertCell(); mark.className = "status";
    if (agent !== "*") mark.id = `status-${agent}`;
  }
}

// a robot's status in the table: failed, done (its state), stuck (or fruitless), idle or
// waiting (its run-health activity), else what it does
function statusOf(a) {
  if (a.kind !== "robot") return ["", ""];
  const activity = a.health || "";
  if (a.state === "failed") return ["failed", "failed"];
  if (a.state === "done") return ["done", activity && activity !== "idle" ? `done, ${activity}` : "done"];
  if (activity === "stuck" || activity === "fruitless") return ["stuck", activity];
  if (activity === "idle" || activity === "waiting") return [activity, activity];
  return ["", activity || a.state];
}

function updateStatus() {
  for (const a of state.agents) {
    const cell = $(`status-${a.name}`);
    if (!cell) continue;
    const [cls, text] = statusOf(a);
    cell.className = `status ${cls}`;
    cell.textContent = text;
  }
}

function allHave(name) {
  const robots = robotNames();
  return robots.length > 0 && robots.every((n) => state.layers.robots[n].includes(name));
}

function robotNames() { return state.info.names.filter((n, i) => state.info.kinds[i] === "robot"); }

function setRobotLayer(agent, name, on) {
  const agents = agent === "*" ? robotNames() : [agent];
  for (const a of agents) toggle(state.layers.robots[a], name, on);
}

function syncPanel() {
  const info = state.info;
  for (const name of info.robot_layers) {
    $(`all-${name}`).checked = allHave(name);
    for (const a of info.names) $(`layer-${a}-${name}`).checked = state.layers.robots[a].includes(name);
  }
}

function toggleColumn(k) {
  const name = state.info.robot_layers[k];
  if (!name) return;
  setRobotLayer("*", name, !allHave(name));
  syncPanel();
  requestFrame();
}

function drawMarks() {
  const marks = $("marks");
  marks.replaceChildren();
  const total = Math.max(state.info.steps - 1, 1);
  for (const [n, text] of state.timeline.events) {
    const b = document.createElement("button");
    b.style.left = `${(100 * n) / total}%`;
    b.title = `step ${state.timeline.steps[n] ?? n}: ${text}`;
    b.className = "mark";
    b.addEventListener("click", () => { setPlaying(false); seek(n); });
    marks.append(b);
  }
}

function drawChart() {
  const canvas = $("chart"), ctx = canvas.getContext("2d");
  const w = canvas.width, h = canvas.height, tl = state.timeline;
  const total = Math.max((state.info ? state.info.steps : 1) - 1, 1);
  ctx.clearRect(0, 0, w, h);
  ctx.strokeStyle = "#ccc"; ctx.strokeRect(0.5, 0.5, w - 1, h - 1);
  const line = (values, colour) => {
    ctx.strokeStyle = colour; ctx.beginPath();
    values.forEach((v, i) => { const x = (i / total) * w, y = h - v * (h - 4) - 2; i ? ctx.lineTo(x, y) : ctx.moveTo(x, y); });
    ctx.stroke();
  };
  line(tl.explored, "#1f5fbf");
  line(tl.known_at_base, "#d9780b");
  ctx.strokeStyle = "#c33"; // events (doors, collapses, failures), as on the timeline
  for (const [n] of tl.events) {
    const ex = Math.round((n / total) * w) + 0.5;
    ctx.beginPath(); ctx.moveTo(ex, 0); ctx.lineTo(ex, 10); ctx.stroke();
  }
  const x = Math.round((state.n / total) * w) + 0.5;
  ctx.strokeStyle = "#000"; ctx.beginPath(); ctx.moveTo(x, 0); ctx.lineTo(x, h); ctx.stroke();
}

function onHover(ev) {
  const canvas = $("frame"), tip = $("hover");
  const rect = canvas.getBoundingClientRect(), view = $("view").getBoundingClientRect();
  const fx = ((ev.clientX - rect.left) * canvas.width) / rect.width;
  const fy = ((ev.clientY - rect.top) * canvas.height) / rect.height;
  const hits = state.agents.filter((a) => Math.hypot(a.px[0] - fx, a.px[1] - fy) <= a.r + 4);
  if (!hits.length || state.drag) { tip.hidden = true; return; }
  tip.textContent = hits.map(hoverText).join("\n\n");
  tip.style.left = `${ev.clientX - view.left + 12}px`;
  tip.style.top = `${ev.clientY - view.top + 12}px`;
  tip.hidden = false;
}

function hoverText(hit) {
  const battery = hit.battery === null ? "none" : `${(100 * hit.battery).toFixed(1)} %`;
  const contact = hit.base_contact < 0 ? "never" : `step ${hit.base_contact}`;
  return [
    `${hit.name} (${hit.kind})`, `state      ${hit.state}${hit.parts ? " (" + hit.parts.join(", ") + " broken)" : ""}`,
    `activity   ${hit.health || "-"}`,
    `role       ${hit.role}`, `travelled  ${hit.distance} cells`, `path left  ${hit.path_left} cells`,
    `battery    ${battery}`, `base heard ${contact}`,
    `presumes lost ${hit.lost ? hit.lost.join(", ") : "-"}`,
    ...(hit.localization ? [believedLine(hit.localization)] : []),
    ...(hit.meetings ? hit.meetings.map(meetingLine) : []),
  ].join("\n");
}

// zoom and pan: a CSS transform of the frame inside #view; pixels stay crisp (pixelated)
// from 2x, smooth when the frame is shown smaller than drawn
function applyView() {
  const v = state.view, canvas = $("frame");
  canvas.style.transform = `translate(${v.x}px, ${v.y}px) scale(${v.zoom})`;
  canvas.style.imageRendering = v.zoom >= 2 ? "pixelated" : "auto";
  $("zoom").textContent = `zoom ${v.zoom.toFixed(v.zoom < 10 ? 1 : 0)}x`;
}

function zoomAt(factor, cx, cy) {
  const v = state.view, zoom = Math.min(32, Math.max(1, v.zoom * factor));
  v.x = cx - ((cx - v.x) * zoom) / v.zoom; v.y = cy - ((cy - v.y) * zoom) / v.zoom;
  v.zoom = zoom;
  if (zoom === 1) { v.x = 0; v.y = 0; }
  applyView();
}

function zoomCentre(factor) {
  const box = $("view").getBoundingClientRect();
  zoomAt(factor, box.width / 2, box.height / 2);
}

function panBy(dx, dy) { state.view.x += dx; state.view.y += dy; applyView(); }

function resetView() { state.view = { zoom: 1, x: 0, y: 0 }; applyView(); }

function onWheel(ev) {
  ev.preventDefault();
  const box = $("view").getBoundingClientRect();
  zoomAt(ev.deltaY < 0 ? 1.25 : 0.8, ev.clientX - box.left, ev.clientY - box.top);
}

function onDrag(ev) {
  if (ev.type === "mousedown") { state.drag = { x: ev.clientX, y: ev.clientY }; $("view").classList.add("dragging"); return; }
  if (!state.drag) return;
  if (ev.type === "mouseup" || ev.type === "mouseleave") { state.drag = null; $("view").classList.remove("dragging"); return; }
  panBy(ev.clientX - state.drag.x, ev.clientY - state.drag.y);
  state.drag = { x: ev.clientX, y: ev.clientY };
}

function believedLine(b) {
  // the localization feature's hover entry: believed position, heading, error and sigma (cells)
  return `believed   ${b.believed.join(", ")} at ${b.heading_deg} deg, error ${b.error}, sigma ${b.sigma} cells`;
}

function meetingLine(m) {
  // a pending meeting (rendezvous accounting): partner, this agent's point, agreed step, window end
  const at = m.at ? ` at ${m.at.join(", ")}` : "";
  return `meeting    with ${m.with}${at}, step ${m.step} (window to ${m.closes})`;
}

function onKey(ev) {
  if (ev.target.tagName === "SELECT") return;
  const pan = { ArrowLeft: [40, 0], ArrowRight: [-40, 0], ArrowUp: [0, 40], ArrowDown: [0, -40] };
  if (ev.shiftKey && pan[ev.key]) { ev.preventDefault(); panBy(...pan[ev.key]); }
  else if (ev.key === " ") { ev.preventDefault(); setPlaying(!state.playing); }
  else if (ev.key === "ArrowRight") { ev.preventDefault(); stepBy(1); }
  else if (ev.key === "ArrowLeft") { ev.preventDefault(); stepBy(-1); }
  else if (ev.key === "+" || ev.key === "=") { zoomCentre(1.25); }
  else if (ev.key === "-") { zoomCentre(0.8); }
  else if (ev.key === "z") { resetView(); }
  else if (/^[0-9]$/.test(ev.key)) { toggleColumn((Number(ev.key) + 9) % 10); }
}

function init() {
  $("play").addEventListener("click", () => setPlaying(!state.playing));
  $("back").addEventListener("click", () => stepBy(-1));
  $("fwd").addEventListener("click", () => stepBy(1));
  $("stop").addEventListener("click", () => send({ op: "stop" }));
  $("speed").addEventListener("change", (ev) => {
    state.speed = Number(ev.target.value);
    if (live()) send({ op: "speed", value: state.speed });
  });
  $("scrub").addEventListener("input", (ev) => { const n = Number(ev.target.value); setPlaying(false); seek(n); });
  $("chart").addEventListener("click", (ev) => {
    const rect = ev.target.getBoundingClientRect();
    seek(Math.round(((ev.clientX - rect.left) / rect.width) * (state.info.steps - 1)));
  });
  $("frame").addEventListener("mousemove", onHover);
  $("frame").addEventListener("mouseleave", () => { $("hover").hidden = true; });
  const view = $("view");
  view.addEventListener("wheel", onWheel, { passive: false });
  for (const type of ["mousedown", "mousemove", "mouseup", "mouseleave"]) view.addEventListener(type, onDrag);
  document.addEventListener("keydown", onKey);
  state.speed = Number($("speed").value);
  connect();
}

init();
