// omnibot dashboard: draws what the server streams and sends what the user does (docs/dashboard.md).
//
// server -> page: scene (robot, world, path), trail, state (20 Hz), log, error, pong
// page -> server: drive (keys, on-screen stick), joy (gamepad), estop, resume, teach, ping
//
// Driving repeats its message every 50 ms while input is held and sends one "enable: false" when
// it ends; the server stops the robot if the repeats stop coming.

const SEND_PERIOD = 50; // ms
const CHART_SAMPLES = 200; // 10 s at 20 Hz
const $ = (id) => document.getElementById(id);

const SCAN_COLOR = "#e11d48";
let ws = null;
let scene = null;
let state = null;
let trail = [];
let scan = null; // the latest scan the state frames carried: {t, points: [[x, y], ...]} in the world
let view = null; // {x0, y0, x1, y1}: the part of the world shown
let lastPing = 0;
let pageRtt = null;

// ------------------------------------------------------------------ connection

function connect() {
  const token = new URLSearchParams(location.search).get("token");
  const proto = location.protocol === "https:" ? "wss" : "ws";
  const url = `${proto}://${location.host}/ws` + (token ? `?token=${encodeURIComponent(token)}` : "");
  ws = new WebSocket(url);
  ws.onopen = () => setPill("link", "connected", "pill-ok");
  ws.onclose = () => {
    setPill("link", "disconnected: reconnecting", "pill-bad");
    setTimeout(connect, 1000);
  };
  ws.onmessage = (ev) => receive(JSON.parse(ev.data));
}

function sendRaw(text) {
  if (ws && ws.readyState === WebSocket.OPEN) ws.send(text);
}

function send(message) {
  sendRaw(JSON.stringify(message));
}

function receive(msg) {
  switch (msg.type) {
    case "scene":
      scene = msg;
      $("robot-name").textContent = msg.robot.name;
      setupTeach(msg.teach);
      view = null;
      break;
    case "trail":
      trail = msg.points;
      break;
    case "state":
      onState(msg);
      break;
    case "log":
      addLog(msg.level, msg.text);
      break;
    case "error":
      showError(msg.error);
      addLog("error", msg.error);
      break;
    case "pong":
      pageRtt = performance.now() - msg.t;
      break;
  }
}

// ------------------------------------------------------------------ state

function onState(s) {
  state = s;
  if (s.scan) {
    scan = s.scan;
    $("legend-scan").hidden = false;
  }
  if (s.pose) {
    const last = trail[trail.length - 1];
    if (!last || Math.abs(s.pose[0] - last[0]) + Math.abs(s.pose[1] - last[1]) >= 0.005) trail.push([s.pose[0], s.pose[1]]);
    if (trail.length > 5000) trail.shift();
  }
  const fmt = (v, d = 2) => (v === null || v === undefined ? "-" : v.toFixed(d));
  $("pose").textContent = s.pose
    ? `x ${fmt(s.pose[0])} m, y ${fmt(s.pose[1])} m, ${fmt((s.pose[2] * 180) / Math.PI, 0)}° (${s.pose_source})`
    : "unknown";
  $("legend-odo").hidden = !(s.odometry && s.pose_source === "truth"); // the ghost is drawn only then
  const d = s.drive;
  $("twist").textContent = d.twist
    ? `vx ${fmt(d.twist[0])} m/s, vy ${fmt(d.twist[1])} m/s, w ${fmt(d.twist[2])} rad/s`
    : "none";
  $("control").textContent = d.reason
    ? d.latched
      ? d.latch_reason === "battery"
        ? `${d.reason}; the controller stopped: battery flat (charge it, then STOP)`
        : `${d.reason}; the controller latched its emergency stop`
      : d.reason
    : "-";
  $("robot-state").textContent = s.robot_state || "-";
  $("battery").textContent = s.battery
    ? `${fmt(s.battery)} V${s.battery_level && s.battery_level !== "ok" ? ` (${s.battery_level})` : ""}`
    : "-";
  $("battery").classList.toggle("battery-warn", ["low", "limited", "flat"].includes(s.battery_level));
  $("ranges").textContent = s.ranges
    ? s.ranges.map((r, i) => `${scene?.robot.sonars[i]?.name ?? i + 1}: ${r === null ? "no echo" : `${Math.round(r * 100)} cm`}`).join(", ")
    : "-";
  const l = s.link;
  $("link-detail").textContent =
    `TEL ${l.tel_hz} Hz, VEL round trip ${l.rtt_ms ?? "-"} ms, page ${pageRtt === null ? "-" : pageRtt.toFixed(0)} ms, errors ${l.errors}`;
  if (ws && ws.readyState === WebSocket.OPEN) {
    setPill("link", l.ok ? `link ok: ${l.url}` : `link error: ${l.error}`, l.ok ? "pill-ok" : "pill-bad");
  }
  const ds = d.state;
  const label = ds === "estop" ? "E-STOP" : ds === "driving" ? `driving (${d.source})` : ds === "stopping" ? `stopping (${d.ended})` : ds;
  setPill("drive-state", label, ds === "estop" ? "pill-estop" : ds === "driving" ? "pill-driving" : "");
  $("estop").classList.toggle("engaged", ds === "estop");
  $("resume").disabled = ds !== "estop";
  pushCharts(s);
  requestDraw();
}

function setPill(id, text, cls) {
  const el = $(id);
  el.textContent = text;
  el.className = `pill ${cls}`;
}

let errorTimer = null;
function showError(text) {
  const el = $("error");
  el.textContent = text;
  el.hidden = false;
  clearTimeout(errorTimer);
  errorTimer = setTimeout(() => (el.hidden = true), 8000);
}

function addLog(level, text) {
  const li = document.createElement("li");
  li.className = level;
  li.textContent = `${new Date().toLocaleTimeString()} ${text}`;
  const log = $("log");
  log.prepend(li);
  while (log.children.length > 50) log.lastChild.remove();
}

// ------------------------------------------------------------------ map

const SURFACES = { wood: "#f1e4c8", carpet: "#e2d4ee", concrete: "#e3e4e6", linoleum: "#d7ecdf" };
let drawQueued = false;

function requestDraw() {
  if (!drawQueued) {
    drawQueued = true;
    requestAnimationFrame(() => {
      drawQueued = false;
      drawMap();
      drawCharts();
    });
  }
}

function fitCanvas(canvas) {
  const r = canvas.getBoundingClientRect();
  const dpr = window.devicePixelRatio || 1;
  const w = Math.max(1, Math.round(r.width * dpr));
  const h = Math.max(1, Math.round(r.height * dpr));
  if (canvas.width !== w || canvas.height !== h) {
    canvas.width = w;
    canvas.height = h;
  }
  const ctx = canvas.getContext("2d");
  ctx.setTransform(dpr, 0, 0, dpr, 0, 0);
  return [ctx, r.width, r.height];
}

function chooseView() {
  const pose = state?.pose ?? [0, 0, 0];
  const b = scene?.world?.bounds;
  if (b) return { x0: b[0] - 0.3, y0: b[1] - 0.3, x1: b[2] + 0.3, y1: b[3] + 0.3 };
  // no map: a 4 m window that follows the robot
  if (!view || pose[0] < view.x0 + 0.5 || pose[0] > view.x1 - 0.5 || pose[1] < view.y0 + 0.5 || pose[1] > view.y1 - 0.5) {
    return { x0: pose[0] - 2, y0: pose[1] - 2, x1: pose[0] + 2, y1: pose[1] + 2 };
  }
  return view;
}

function drawMap() {
  const [ctx, W, H] = fitCanvas($("map"));
  ctx.clearRect(0, 0, W, H);
  if (!scene) return;
  view = chooseView();
  const s = Math.min(W / (view.x1 - view.x0), H / (view.y1 - view.y0));
  const ox = (W - s * (view.x1 - view.x0)) / 2;
  const oy = (H + s * (view.y1 - view.y0)) / 2;
  const P = (x, y) => [ox + (x - view.x0) * s, oy - (y - view.y0) * s];
  const poly = (pts, close = true) => {
    ctx.beginPath();
    pts.forEach(([x, y], i) => (i ? ctx.lineTo(...P(x, y)) : ctx.moveTo(...P(x, y))));
    if (close) ctx.closePath();
  };
  const world = scene.world;
  // floor, grid
  ctx.fillStyle = world ? SURFACES[world.floor] ?? "#eee" : "#fafafa";
  if (world && world.bounds) {
    const [bx0, by0, bx1, by1] = world.bounds;
    poly([[bx0, by0], [bx1, by0], [bx1, by1], [bx0, by1]]);
    ctx.fill();
  } else ctx.fillRect(0, 0, W, H);
  ctx.strokeStyle = "rgba(0,0,0,0.06)";
  ctx.lineWidth = 1;
  for (let gx = Math.ceil(view.x0 * 2) / 2; gx <= view.x1; gx += 0.5) {
    ctx.beginPath(); ctx.moveTo(...P(gx, view.y0)); ctx.lineTo(...P(gx, view.y1)); ctx.stroke();
  }
  for (let gy = Math.ceil(view.y0 * 2) / 2; gy <= view.y1; gy += 0.5) {
    ctx.beginPath(); ctx.moveTo(...P(view.x0, gy)); ctx.lineTo(...P(view.x1, gy)); ctx.stroke();
  }
  if (world) {
    for (const p of world.patches) {
      ctx.fillStyle = SURFACES[p.surface] ?? "#ddd";
      poly(p.points); ctx.fill();
      ctx.fillStyle = "rgba(0,0,0,0.35)";
      ctx.font = "11px system-ui";
      const [lx, ly] = P(p.points[0][0] + 0.05, p.points[0][1] + 0.05);
      ctx.fillText(p.surface, lx, ly);
    }
    ctx.fillStyle = "#9aa3ad";
    for (const o of world.obstacles) { poly(o); ctx.fill(); }
    ctx.strokeStyle = "#2b3038";
    ctx.lineWidth = 3;
    for (const [x0, y0, x1, y1] of world.segments) {
      ctx.beginPath(); ctx.moveTo(...P(x0, y0)); ctx.lineTo(...P(x1, y1)); ctx.stroke();
    }
  }
  // planned path, trail
  if (scene.path) {
    ctx.setLineDash([8, 6]);
    ctx.strokeStyle = "#ea8a0c";
    ctx.lineWidth = 2.5;
    poly(scene.path, false); ctx.stroke();
    ctx.setLineDash([]);
  }
  if (trail.length > 1) {
    ctx.strokeStyle = "#2563eb";
    ctx.lineWidth = 2;
    poly(trail, false); ctx.stroke();
  }
  // the latest scan's returns
  if (scan) {
    ctx.fillStyle = SCAN_COLOR;
    for (const [px, py] of scan.points) {
      const [sx, sy] = P(px, py);
      ctx.fillRect(sx - 2, sy - 2, 4, 4);
    }
  }
  // scale bar
  ctx.fillStyle = "#374151";
  ctx.fillRect(12, H - 16, s, 3);
  ctx.font = "11px system-ui";
  ctx.fillText("1 m", 12, H - 22);
  if (!state?.pose) return;
  const [x, y, th] = state.pose;
  const toWorld = (bx, by, px = x, py = y, pth = th) => [px + bx * Math.cos(pth) - by * Math.sin(pth), py + bx * Math.sin(pth) + by * Math.cos(pth)];
  const robot = scene.robot;
  // sonar cones with their readings
  robot.sonars.forEach((so, i) => {
    const r = state.ranges ? state.ranges[i] : null;
    const reach = r ?? so.max_range;
    const [sx, sy] = toWorld(so.x, so.y);
    const a = th + so.angle;
    ctx.beginPath();
    ctx.moveTo(...P(sx, sy));
    const steps = 12;
    for (let k = 0; k <= steps; k++) {
      const ak = a - so.cone / 2 + (so.cone * k) / steps;
      ctx.lineTo(...P(sx + reach * Math.cos(ak), sy + reach * Math.sin(ak)));
    }
    ctx.closePath();
    ctx.fillStyle = r === null ? "rgba(14,165,233,0.07)" : "rgba(14,165,233,0.22)";
    ctx.fill();
    if (r !== null) {
      const [lx, ly] = P(sx + (reach + 0.05) * Math.cos(a), sy + (reach + 0.05) * Math.sin(a));
      ctx.fillStyle = "#0369a1";
      ctx.font = "bold 12px system-ui";
      ctx.fillText(`${Math.round(r * 100)} cm`, lx, ly);
    }
  });
  // odometry ghost (when the pose shown is the simulator's truth)
  if (state.odometry && state.pose_source === "truth") {
    const [qx, qy, qth] = state.odometry;
    ctx.setLineDash([4, 4]);
    ctx.strokeStyle = "#9333ea";
    ctx.lineWidth = 1.5;
    poly(robot.footprint.map(([bx, by]) => toWorld(bx, by, qx, qy, qth))); ctx.stroke();
    ctx.setLineDash([]);
  }
  // footprint, wheels, heading
  poly(robot.footprint.map(([bx, by]) => toWorld(bx, by)));
  ctx.fillStyle = "rgba(37,99,235,0.14)";
  ctx.fill();
  ctx.strokeStyle = "#1e3a8a";
  ctx.lineWidth = 2;
  ctx.stroke();
  robot.wheels.forEach((w, i) => {
    const ca = Math.cos(w.angle), sa = Math.sin(w.angle);
    const hl = w.radius, hw = w.width / 2;
    const corners = [[-hl, -hw], [hl, -hw], [hl, hw], [-hl, hw]].map(([u, v]) => toWorld(w.x + u * ca - v * sa, w.y + u * sa + v * ca));
    poly(corners);
    const p = state.powers ? state.powers[i] ?? 0 : 0;
    ctx.fillStyle = p > 0 ? "#15803d" : p < 0 ? "#b91c1c" : "#374151";
    ctx.fill();
  });
  ctx.strokeStyle = "#1e3a8a";
  ctx.lineWidth = 2.5;
  const nose = toWorld(Math.max(...robot.footprint.map((q) => q[0])) * 0.9, 0);
  ctx.beginPath(); ctx.moveTo(...P(x, y)); ctx.lineTo(...P(...nose)); ctx.stroke();
}

// ------------------------------------------------------------------ charts

const COLORS = ["#2563eb", "#dc2626", "#16a34a", "#d97706", "#7c3aed", "#0891b2"];
const charts = {
  powers: { id: "chart-powers", series: [] },
  speeds: { id: "chart-speeds", series: [] },
  heading: { id: "chart-heading", series: [], names: ["heading"] },
  battery: { id: "chart-battery", series: [], names: ["battery"] },
  link: { id: "chart-link", series: [], names: ["TEL Hz", "RTT ms"] },
};

function push(chart, values, names) {
  values.forEach((v, i) => {
    chart.series[i] = chart.series[i] || [];
    chart.series[i].push(v);
    if (chart.series[i].length > CHART_SAMPLES) chart.series[i].shift();
  });
  if (names) chart.names = names;
}

function pushCharts(s) {
  const wheelNames = scene ? scene.robot.wheels.map((w) => w.name) : [];
  if (s.powers) push(charts.powers, s.powers, wheelNames);
  if (s.wheel_speeds) push(charts.speeds, s.wheel_speeds, wheelNames);
  if (s.heading !== null) push(charts.heading, [(s.heading * 180) / Math.PI]);
  if (s.battery !== null) push(charts.battery, [s.battery]);
  push(charts.link, [s.link.tel_hz, s.link.rtt_ms ?? 0]);
}

function drawCharts() {
  for (const chart of Object.values(charts)) drawChart(chart);
}

function drawChart(chart) {
  const [ctx, W, H] = fitCanvas($(chart.id));
  ctx.clearRect(0, 0, W, H);
  const all = chart.series.flat().filter((v) => v !== null && Number.isFinite(v));
  if (!all.length) {
    ctx.fillStyle = "#9ca3af";
    ctx.font = "12px system-ui";
    ctx.fillText("no data", 8, H / 2);
    return;
  }
  let lo = Math.min(...all), hi = Math.max(...all);
  if (hi - lo < 1e-6) { lo -= 1; hi += 1; }
  const pad = (hi - lo) * 0.1;
  lo -= pad; hi += pad;
  const L = 34, R = W - 4, T = 4, B = H - 16;
  const X = (i) => L + ((R - L) * i) / (CHART_SAMPLES - 1);
  const Y = (v) => B - ((v - lo) / (hi - lo)) * (B - T);
  ctx.strokeStyle = "#e5e7eb";
  ctx.beginPath(); ctx.moveTo(L, T); ctx.lineTo(L, B); ctx.lineTo(R, B); ctx.stroke();
  if (lo < 0 && hi > 0) { ctx.beginPath(); ctx.moveTo(L, Y(0)); ctx.lineTo(R, Y(0)); ctx.stroke(); }
  ctx.fillStyle = "#6b7280";
  ctx.font = "10px system-ui";
  ctx.fillText(hi.toPrecision(3), 2, T + 8);
  ctx.fillText(lo.toPrecision(3), 2, B);
  chart.series.forEach((ys, k) => {
    const off = CHART_SAMPLES - ys.length;
    ctx.strokeStyle = COLORS[k % COLORS.length];
    ctx.lineWidth = 1.5;
    ctx.beginPath();
    ys.forEach((v, i) => (i ? ctx.lineTo(X(off + i), Y(v)) : ctx.moveTo(X(off + i), Y(v))));
    ctx.stroke();
  });
  (chart.names || []).forEach((name, k) => {
    ctx.fillStyle = COLORS[k % COLORS.length];
    ctx.fillText(name, L + 4 + k * 46, H - 3);
  });
}

// ------------------------------------------------------------------ driving

const keys = new Set();
const stick = { active: false, x: 0, y: 0 }; // x right, y up, unit disc
let turn = 0;
let driving = false;

const KEYMAP = {
  KeyW: ["vx", 1], ArrowUp: ["vx", 1], KeyS: ["vx", -1], ArrowDown: ["vx", -1],
  KeyA: ["vy", 1], KeyD: ["vy", -1], KeyQ: ["w", 1], ArrowLeft: ["w", 1], KeyE: ["w", -1], ArrowRight: ["w", -1],
};

function driveCommand() {
  const cmd = { vx: 0, vy: 0, w: 0 };
  const level = keys.has("Shift") ? 1 : 0.5;
  for (const k of keys) if (KEYMAP[k]) cmd[KEYMAP[k][0]] += KEYMAP[k][1] * level;
  let source = "keyboard";
  if (stick.active) {
    cmd.vx += stick.y;
    cmd.vy += -stick.x;
    source = "joystick";
  }
  cmd.w += turn;
  for (const k of ["vx", "vy", "w"]) cmd[k] = Math.max(-1, Math.min(1, cmd[k]));
  const held = stick.active || turn !== 0 || [...keys].some((k) => KEYMAP[k]);
  return { held, cmd, source };
}

function driveTick() {
  const { held, cmd, source } = driveCommand();
  if (held) {
    send({ type: "drive", ...cmd, enable: true, source });
    driving = true;
  } else if (driving) {
    send({ type: "drive", vx: 0, vy: 0, w: 0, enable: false, source });
    driving = false;
  }
  pollGamepad();
  if (performance.now() - lastPing > 1000) {
    lastPing = performance.now();
    send({ type: "ping", t: lastPing });
  }
}

function releaseAll() {
  keys.clear();
  stick.active = false;
  stick.x = stick.y = 0;
  turn = 0;
  $("turn").value = 0;
  drawStick();
}

function estop() {
  releaseAll();
  send({ type: "estop" });
}

document.addEventListener("keydown", (ev) => {
  if (ev.target instanceof HTMLInputElement && ev.target.type !== "range") return;
  if (ev.code === "Space") {
    ev.preventDefault();
    if (document.activeElement instanceof HTMLElement) document.activeElement.blur(); // no button click on keyup
    estop();
    return;
  }
  if (ev.key === "Shift") keys.add("Shift");
  if (KEYMAP[ev.code]) { ev.preventDefault(); keys.add(ev.code); }
});
document.addEventListener("keyup", (ev) => {
  if (ev.key === "Shift") keys.delete("Shift");
  keys.delete(ev.code);
});
window.addEventListener("blur", releaseAll); // a key released in another window never comes back
document.addEventListener("visibilitychange", () => document.hidden && releaseAll());

// on-screen joystick
function drawStick() {
  const c = $("stick");
  const ctx = c.getContext("2d");
  const r = c.width / 2;
  ctx.clearRect(0, 0, c.width, c.height);
  ctx.fillStyle = "#eef2f7";
  ctx.beginPath(); ctx.arc(r, r, r - 2, 0, 2 * Math.PI); ctx.fill();
  ctx.strokeStyle = "#cbd5e1";
  ctx.beginPath(); ctx.moveTo(r, 8); ctx.lineTo(r, 2 * r - 8); ctx.moveTo(8, r); ctx.lineTo(2 * r - 8, r); ctx.stroke();
  ctx.fillStyle = stick.active ? "#2563eb" : "#64748b";
  ctx.beginPath(); ctx.arc(r + stick.x * (r - 24), r - stick.y * (r - 24), 22, 0, 2 * Math.PI); ctx.fill();
}

function stickFrom(ev) {
  const c = $("stick");
  const b = c.getBoundingClientRect();
  const r = b.width / 2;
  let x = (ev.clientX - b.left - r) / (r - 24);
  let y = -(ev.clientY - b.top - r) / (r - 24);
  const m = Math.hypot(x, y);
  if (m > 1) { x /= m; y /= m; }
  stick.x = x; stick.y = y;
  drawStick();
}

$("stick").addEventListener("pointerdown", (ev) => {
  $("stick").setPointerCapture(ev.pointerId);
  stick.active = true;
  stickFrom(ev);
});
$("stick").addEventListener("pointermove", (ev) => stick.active && stickFrom(ev));
for (const type of ["pointerup", "pointercancel", "lostpointercapture"]) {
  $("stick").addEventListener(type, () => {
    stick.active = false; stick.x = stick.y = 0; drawStick();
  });
}
$("turn").addEventListener("input", (ev) => (turn = Number(ev.target.value)));
for (const type of ["pointerup", "pointercancel", "change"]) {
  $("turn").addEventListener(type, () => { turn = 0; $("turn").value = 0; });
}

// gamepad (Gamepad API, standard layout): mapped on the server with the teleop config
let gamepadIndex = null;
window.addEventListener("gamepadconnected", (ev) => {
  gamepadIndex = ev.gamepad.index;
  $("gamepad").textContent = `Gamepad: ${ev.gamepad.id} (hold the enable button to drive)`;
});
window.addEventListener("gamepaddisconnected", (ev) => {
  if (ev.gamepad.index !== gamepadIndex) return;
  gamepadIndex = null;
  $("gamepad").textContent = "Gamepad disconnected.";
  send({ type: "drive", vx: 0, vy: 0, w: 0, enable: false });
});

function pollGamepad() {
  if (gamepadIndex === null || !navigator.getGamepads) return;
  const gp = navigator.getGamepads()[gamepadIndex];
  if (!gp) return;
  send({
    type: "joy",
    axes: gp.axes.slice(0, 16).map((a) => Math.max(-1, Math.min(1, a))),
    buttons: gp.buttons.slice(0, 32).map((b) => (b.pressed ? 1 : Math.max(0, Math.min(1, b.value)))),
  });
}

// buttons
$("estop").addEventListener("click", estop);
$("resume").addEventListener("click", () => send({ type: "resume" }));

function setupTeach(available) {
  for (const b of document.querySelectorAll("[data-teach]")) {
    b.disabled = !available;
    b.onclick = () => send({ type: "teach", action: b.dataset.teach });
  }
  $("teach-note").textContent = available
    ? "Teach records the path you drive; Stop ends it; Repeat drives to its start and follows it."
    : "Not enabled on this server (omnibot dashboard enables it).";
}

window.addEventListener("resize", requestDraw);
window.omnibot = { send, sendRaw, state: () => state, trail: () => trail, scene: () => scene, scan: () => scan };
drawStick();
connect();
setInterval(driveTick, SEND_PERIOD);
