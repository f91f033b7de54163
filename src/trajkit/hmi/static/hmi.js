// trajkit HMI page: talks to the JSON API and listens to the live WebSocket.
// Every value is validated by the server; this page only shows its answers.
"use strict";
(function () {
  const $ = (id) => document.getElementById(id);
  const params = new URLSearchParams(location.search);
  const TOKEN = params.get("token");
  const HISTORY_S = 20;
  let jobLoaded = false, plannedPath = [], trail = [], axesKey = "", charts = null;
  let chartData = null, t0 = null, lastState = null, lastTool = null, steps = [], lastRun = null, jogging = false;
  let lastJobId = null;

  // ------------------------------------------------------------------ API
  function showMsg(text, isError) {
    const m = $("msg");
    m.textContent = text || "";
    m.className = "msg" + (isError ? " error" : "");
  }
  let CSRF = null;  // this server's anti-CSRF value (GET /api/session), sent on every change
  async function loadSession() {
    try {
      const res = await fetch("/api/session", { headers: TOKEN ? { "X-Trajkit-Token": TOKEN } : {} });
      if (res.ok) CSRF = (await res.json()).csrf_token;
    } catch (e) { /* offline: the next request says so */ }
  }
  async function api(method, path, body, retried) {
    const headers = {};
    if (body !== undefined) headers["Content-Type"] = "application/json";
    if (TOKEN) headers["X-Trajkit-Token"] = TOKEN;
    if (method !== "GET" && CSRF) headers["X-Trajkit-CSRF"] = CSRF;
    let res;
    try {
      res = await fetch(path, { method, headers, body: body === undefined ? undefined : JSON.stringify(body) });
    } catch (e) {
      showMsg("server unreachable: " + e, true);
      return null;
    }
    const data = await res.json().catch(() => ({}));
    if (res.status === 403 && !retried && String(data.error || "").includes("X-Trajkit-CSRF")) {
      await loadSession();  // the server restarted: take its new value and send once more
      return api(method, path, body, true);
    }
    if (!res.ok) {
      showMsg(data.error || ("HTTP " + res.status), true);
      return null;
    }
    return data;
  }
  // form text to a JSON number when it is one; anything else goes as typed and the
  // server names the field ("Input should be a valid number")
  const num = (text) => { const t = String(text).trim(); const n = Number(t); return t !== "" && Number.isFinite(n) ? n : t; };

  // ------------------------------------------------------------------ tabs and forms
  document.querySelectorAll(".tab").forEach((tab) => tab.addEventListener("click", () => selectTab(tab.dataset.tab)));
  function selectTab(name) {
    document.querySelectorAll(".tab").forEach((t) => t.classList.toggle("active", t.dataset.tab === name));
    document.querySelectorAll(".tabpane").forEach((p) => p.classList.toggle("active", p.dataset.kind === name));
  }
  document.querySelectorAll("form.tabpane").forEach((form) => form.addEventListener("submit", async (ev) => {
    ev.preventDefault();
    const body = { kind: form.dataset.kind };
    for (const el of form.elements) {
      if (!el.name) continue;
      body[el.name] = el.tagName === "INPUT" && el.inputMode ? num(el.value) : el.value;
    }
    form.querySelectorAll("input").forEach((i) => i.classList.remove("bad"));
    showMsg("planning " + body.kind + " job ...");
    const res = await api("POST", "/api/job", body);
    if (!res) {  // the server unloaded the previous job: nothing to start until a plan succeeds
      const m = $("msg").textContent;
      form.querySelectorAll("input, textarea").forEach((i) => { if (i.name && m.includes(i.name)) i.classList.add("bad"); });
      clearJob();
      return;
    }
    showJob(res);
    showMsg("planned " + res.title + ": " + res.duration_s.toFixed(3) + " s; press Start");
  }));

  function showJob(job) {
    jobLoaded = true;
    plannedPath = job.path_mm || [];
    trail = [];
    $("job-title").textContent = job.title + "  |  " + job.duration_s.toFixed(3) + " s";
    const dl = $("summary");
    dl.replaceChildren();
    const add = (k, v) => { const dt = document.createElement("dt"); dt.textContent = k; const dd = document.createElement("dd"); dd.textContent = v; dl.append(dt, dd); };
    add("Job", job.title);
    for (const row of job.summary_view || []) add(row.label, fmt(row.value) + (row.unit ? " " + row.unit : ""));
    setupAxes(job.axes);
    drawPath(null);
    updateButtons(lastState || "idle");
  }
  function clearJob() {
    jobLoaded = false;
    plannedPath = [];
    trail = [];
    $("job-title").textContent = "no job loaded";
    const dl = $("summary");
    dl.replaceChildren();
    const dt = document.createElement("dt"); dt.textContent = "Job";
    const dd = document.createElement("dd"); dd.textContent = "none";
    dl.append(dt, dd);
    drawPath(null);
    updateButtons(lastState || "idle");
  }
  async function refreshJob() {
    const job = await api("GET", "/api/job");
    if (job && job.axes) showJob(job); else if (job) clearJob();
  }
  const fmt = (v) => (typeof v === "number" ? (Number.isInteger(v) ? String(v) : v.toFixed(3)) : String(v));

  // ------------------------------------------------------------------ axes, charts
  const COLORS = ["#1f6feb", "#d9480f", "#2b8a3e", "#7048e8", "#c2255c", "#0b7285"];
  function cell(cls, unit) {
    const td = document.createElement("td");
    td.className = cls;
    td.append("\u2013");
    const sm = document.createElement("small"); sm.textContent = unit; td.append(sm);
    return td;
  }
  function setValue(td, text) { td.firstChild.nodeValue = text; }
  function setupAxes(axes) {
    const key = axes.map((a) => a.name + a.unit).join("|");
    const tb = $("axes").querySelector("tbody");
    tb.replaceChildren();
    axes.forEach((a, i) => {
      const tr = document.createElement("tr");
      tr.dataset.axis = a.name;
      const name = document.createElement("td");
      name.className = "name";
      name.textContent = a.name;
      name.style.color = COLORS[i % COLORS.length];
      tr.append(name, cell("axis-pos", a.unit), cell("axis-act", a.unit), cell("axis-vel", a.unit + "/s"),
                cell("axis-fe", a.unit));
      tb.append(tr);
    });
    if (!axes.length) {
      const tr = document.createElement("tr"), td = document.createElement("td");
      td.colSpan = 5; td.className = "muted"; td.textContent = "no job loaded";
      tr.append(td); tb.append(tr);
    }
    if (key === axesKey && charts) return;
    axesKey = key;
    buildCharts(axes);
  }
  function buildCharts(axes) {
    for (const id of ["chart-pos", "chart-vel"]) $(id).innerHTML = "";
    chartData = { pos: [[], ...axes.map(() => [])], vel: [[], ...axes.map(() => [])] };
    const width = $("chart-pos").clientWidth || 600;
    const mk = (el, title, unitFn, data) => new uPlot({
      title, width, height: CHART_HEIGHT, legend: { show: true, live: false },
      scales: { x: { time: false } },
      axes: [{ label: "t [s]", size: 34 }, { size: 56 }],
      series: [{ label: "t" }, ...axes.map((a, i) => ({ label: a.name + " [" + unitFn(a.unit) + "]", stroke: COLORS[i % COLORS.length], width: 1.6, points: { show: false } }))],
    }, data, el);
    charts = {
      pos: mk($("chart-pos"), "position", (u) => u, chartData.pos),
      vel: mk($("chart-vel"), "speed", (u) => u + "/s", chartData.vel),
    };
  }
  // the charts follow their panel's width (a narrow window, a resized one)
  const CHART_HEIGHT = window.innerHeight < 900 ? 130 : 170;
  new ResizeObserver(() => {
    if (!charts) return;
    const w = $("chart-pos").clientWidth;
    if (w > 0 && Math.abs(w - charts.pos.width) > 2) {
      charts.pos.setSize({ width: w, height: CHART_HEIGHT });
      charts.vel.setSize({ width: w, height: CHART_HEIGHT });
    }
  }).observe($("chart-pos"));
  function ensureAxes(axes) {
    const key = axes.map((a) => a.name + a.unit).join("|");
    if (key !== axesKey) { setupAxes(axes); clearCharts(); }
  }
  function clearCharts() {
    if (!chartData) return;
    for (const arr of [chartData.pos, chartData.vel]) arr.forEach((a) => { a.length = 0; });
    if (charts) { charts.pos.setData(chartData.pos); charts.vel.setData(chartData.vel); }
  }
  function pushChart(snap) {
    if (!charts || !snap.axes) return;
    const now = snap.server_time;
    if (t0 === null) t0 = now;
    const t = now - t0;
    const { pos, vel } = chartData;
    if (pos[0].length && t <= pos[0][pos[0].length - 1]) return;
    pos[0].push(t); vel[0].push(t);
    snap.axes.forEach((a, i) => { if (pos[i + 1]) { pos[i + 1].push(a.position); vel[i + 1].push(a.velocity); } });
    while (pos[0].length && pos[0][0] < t - HISTORY_S) { pos.forEach((s) => s.shift()); vel.forEach((s) => s.shift()); }
    charts.pos.setData(pos); charts.vel.setData(vel);
  }

  // ------------------------------------------------------------------ path view (isometric)
  function project(p) {
    const c = Math.cos(Math.PI / 6), s = Math.sin(Math.PI / 6);
    return [(p[0] - p[1]) * c, -((p[0] + p[1]) * s) - p[2]];
  }
  function drawPath(tool) {
    const cv = $("path"), ctx = cv.getContext("2d");
    const w = cv.clientWidth || cv.width, h = cv.clientHeight || cv.height;
    if (cv.width !== w) { cv.width = w; cv.height = h; }
    ctx.clearRect(0, 0, cv.width, cv.height);
    const pts = plannedPath.map(project), act = trail.map(project);
    const all = pts.concat(act);
    if (!all.length) { ctx.fillStyle = "#9aa6b2"; ctx.fillText("plan a job to see its path", 16, 24); return; }
    let [x0, y0, x1, y1] = [Infinity, Infinity, -Infinity, -Infinity];
    for (const [x, y] of all) { x0 = Math.min(x0, x); x1 = Math.max(x1, x); y0 = Math.min(y0, y); y1 = Math.max(y1, y); }
    const pad = 24, sc = Math.min((cv.width - 2 * pad) / Math.max(x1 - x0, 1e-9), (cv.height - 2 * pad) / Math.max(y1 - y0, 1e-9));
    const ox = (cv.width - sc * (x1 - x0)) / 2, oy = (cv.height - sc * (y1 - y0)) / 2;
    const tr = ([x, y]) => [ox + sc * (x - x0), oy + sc * (y - y0)];
    const line = (arr, color, width) => {
      if (arr.length < 2) return;
      ctx.strokeStyle = color; ctx.lineWidth = width; ctx.beginPath();
      arr.forEach((p, i) => { const [x, y] = tr(p); if (i) ctx.lineTo(x, y); else ctx.moveTo(x, y); });
      ctx.stroke();
    };
    line(pts, "#b4bec9", 2);
    line(act, "#1f6feb", 2.2);
    if (tool) {
      const [x, y] = tr(project(tool));
      ctx.fillStyle = "#d9480f"; ctx.beginPath(); ctx.arc(x, y, 5, 0, 2 * Math.PI); ctx.fill();
    }
    ctx.fillStyle = "#6b7785"; ctx.font = "11px sans-serif";
    ctx.fillText("isometric view, mm", 10, cv.height - 8);
  }

  // ------------------------------------------------------------------ live link
  function updateButtons(st) {
    const en = (id, on) => { $(id).disabled = !on; };
    en("btn-start", st === "idle" && jobLoaded);
    en("btn-pause", st === "running");
    en("btn-resume", st === "paused" || st === "pausing");
    en("btn-stop", st === "running" || st === "paused" || st === "pausing");
    en("btn-reset", st === "fault");
    // a jog step while a jog moves re-targets it (the server re-plans from the commanded state)
    for (const id of ["jog-minus", "jog-plus"]) en(id, st === "idle" || (st === "running" && jogging));
    for (const id of ["btn-teach", "robot"]) en(id, st === "idle");
  }
  function onLive(snap) {
    const st = snap.state;
    const badge = $("state");
    badge.textContent = st === "fault" ? "E-STOP" : st;
    badge.className = "state state-" + st;
    const jog = st === "running" && snap.motion === "online target";
    if (st !== lastState || jog !== jogging) {
      jogging = jog;
      updateButtons(st);
      if (st === "idle" && lastState !== null) refreshRobot();
      lastState = st;
    }
    if (snap.job_id !== lastJobId) {  // another job loaded or unloaded (this page or another)
      lastJobId = snap.job_id;
      refreshJob();
    }
    if (jobLoaded !== (snap.job !== null)) { jobLoaded = snap.job !== null; updateButtons(st); }
    if (snap.trail_reset) trail = [];
    if (snap.trail && snap.trail.length) trail = trail.concat(snap.trail);
    if (snap.run_id !== lastRun) { lastRun = snap.run_id; t0 = null; clearCharts(); }
    if (snap.axes) {
      ensureAxes(snap.axes);
      const rows = $("axes").querySelectorAll("tbody tr");
      snap.axes.forEach((a, i) => {
        const r = rows[i];
        if (!r || !r.dataset.axis) return;
        setValue(r.querySelector(".axis-pos"), a.position.toFixed(3));
        setValue(r.querySelector(".axis-vel"), a.velocity.toFixed(3));
        setValue(r.querySelector(".axis-act"), a.actual.toFixed(3));
        setValue(r.querySelector(".axis-fe"), a.following_error.toExponential(1));
      });
      pushChart(snap);
    } else if (axesKey !== "") {
      setupAxes([]);
    }
    $("tool-speed").textContent = snap.tool_speed_mm_s === undefined ? "\u2013" : snap.tool_speed_mm_s.toFixed(1);
    if (snap.progress === undefined) {
      $("progress-bar").style.width = "0%";
      $("progress-text").textContent = "";
      $("plan-time").textContent = "t = \u2013";
    } else {
      const pct = Math.max(0, Math.min(100, 100 * snap.progress));
      $("progress-bar").style.width = pct.toFixed(1) + "%";
      $("progress-text").textContent = pct.toFixed(1) + " %";
      $("plan-time").textContent = (snap.motion ? snap.motion + "  |  " : "") + "t = " + snap.plan_time_s.toFixed(3) + " / " + snap.duration_s.toFixed(3) + " s";
    }
    if (document.activeElement !== $("override")) {
      $("override").value = Math.round(snap.override_pct);
      $("override-val").textContent = Math.round(snap.override_pct) + " %";
    }
    for (const e of snap.events || []) addEvent(e);
    lastTool = snap.tool_mm || lastTool;
    drawPath(lastTool);
  }
  function addEvent(e) {
    const li = document.createElement("li");
    li.className = e.level;
    const d = new Date(e.time * 1000);
    const tm = document.createElement("time");
    tm.textContent = d.toLocaleTimeString();
    li.append(tm, document.createTextNode(e.text));
    $("events").prepend(li);
  }
  function connect() {
    const proto = location.protocol === "https:" ? "wss" : "ws";
    const ws = new WebSocket(`${proto}://${location.host}/ws` + (TOKEN ? "?token=" + encodeURIComponent(TOKEN) : ""));
    ws.onopen = () => { $("conn").textContent = "live"; $("conn").classList.add("online"); };
    ws.onmessage = (ev) => onLive(JSON.parse(ev.data));
    ws.onclose = () => { $("conn").textContent = "offline"; $("conn").classList.remove("online"); setTimeout(connect, 1000); };
  }

  // ------------------------------------------------------------------ run control
  for (const cmd of ["start", "pause", "resume", "stop", "estop", "reset"]) {
    $("btn-" + cmd).addEventListener("click", async () => {

      const res = await api("POST", "/api/run/" + cmd);
      if (res) showMsg(cmd === "estop" ? "EMERGENCY STOP: reset the fault to go on" : "", cmd === "estop");
    });
  }
  $("override").addEventListener("input", () => { $("override-val").textContent = $("override").value + " %"; });
  $("override").addEventListener("change", async () => { await api("POST", "/api/override", { percent: num($("override").value) }); });

  // ------------------------------------------------------------------ jog and teach
  async function refreshRobot() {
    const info = await api("GET", "/api/robot");
    if (!info) return;
    $("robot").value = info.robot;
    const sel = $("jog-joint"), keep = sel.value;
    sel.replaceChildren();
    const tb = $("joints").querySelector("tbody");
    tb.replaceChildren();
    const td = (text, cls) => { const c = document.createElement("td"); c.textContent = text; if (cls) c.className = cls; return c; };
    for (const j of info.joints) {
      const o = document.createElement("option");
      o.value = j.name; o.textContent = j.name + " [" + j.unit + "]"; o.dataset.unit = j.unit;
      sel.append(o);
      const tr = document.createElement("tr");
      tr.append(td(j.name), td(j.value.toFixed(3) + " " + j.unit), td(j.min.toFixed(0) + " .. " + j.max.toFixed(0), "muted"));
      tb.append(tr);
    }
    if ([...sel.options].some((o) => o.value === keep)) sel.value = keep;
    $("jog-unit").textContent = sel.selectedOptions[0] ? sel.selectedOptions[0].dataset.unit : "";
    for (const id of ["step-point", "step-via"]) {
      const s = $(id);
      s.replaceChildren();
      if (id === "step-via") s.append(new Option("via \u2013", ""));
      for (const p of Object.keys(info.points)) s.append(new Option(p, p));
    }
  }
  $("jog-joint").addEventListener("change", () => { $("jog-unit").textContent = $("jog-joint").selectedOptions[0].dataset.unit; });
  $("robot").addEventListener("change", async () => { if (await api("POST", "/api/robot", { robot: $("robot").value })) { steps = []; renderSteps(); } refreshRobot(); });
  async function jog(sign) {
    const step = num($("jog-step").value);
    const body = { joint: $("jog-joint").value, step: typeof step === "number" ? sign * step : step,
                   speed_pct: num($("jog-speed").value) };
    if (await api("POST", "/api/jog", body)) showMsg("jogging " + body.joint);
  }
  $("jog-minus").addEventListener("click", () => jog(-1));
  $("jog-plus").addEventListener("click", () => jog(1));
  $("btn-teach").addEventListener("click", async () => {
    const name = $("teach-name").value.trim();
    if (await api("POST", "/api/teach", { name })) {
      showMsg("taught " + name);
      const m = name.match(/^(.*?)(\d+)$/);
      if (m) $("teach-name").value = m[1] + (Number(m[2]) + 1);
      refreshRobot();
    }
  });
  function renderSteps() {
    $("steps").replaceChildren(...steps.map((s) => { const li = document.createElement("li"); li.textContent = s.op + " " + s.point + (s.via ? " via " + s.via : ""); return li; }));
  }
  $("btn-add-step").addEventListener("click", () => {
    const s = { op: $("step-op").value, point: $("step-point").value };
    if ($("step-via").value) s.via = $("step-via").value;
    steps.push(s); renderSteps();
  });
  $("btn-build").addEventListener("click", async () => {
    const res = await api("POST", "/api/program/build", { steps });
    if (!res) return;
    $("program-text").value = res.text;
    selectTab("program");
    showMsg("program built from " + steps.length + " steps: plan, save or edit it");
  });

  // ------------------------------------------------------------------ program files
  async function refreshPrograms() {
    const res = await api("GET", "/api/programs");
    if (!res) return;
    $("program-list").replaceChildren(...res.programs.map((p) => new Option(p, p)));
  }
  $("btn-save").addEventListener("click", async () => {
    const name = $("program-name").value.trim();
    if (await api("POST", "/api/programs", { name, text: $("program-text").value })) {
      showMsg("saved " + name + ".yaml"); refreshPrograms();
    }
  });
  $("btn-load").addEventListener("click", async () => {
    const name = $("program-list").value;
    if (!name) { showMsg("no saved program to load", true); return; }
    const res = await api("GET", "/api/programs/" + encodeURIComponent(name));
    if (res) { $("program-text").value = res.text; $("program-name").value = res.name; showMsg("loaded " + name + ".yaml"); }
  });

  // ------------------------------------------------------------------ start
  (async function init() {
    updateButtons("idle");
    drawPath(null);
    await loadSession();
    const job = await api("GET", "/api/job");
    if (job && job.axes) showJob(job);
    else { clearJob(); setupAxes([]); }
    refreshRobot();
    refreshPrograms();
    connect();
  })();
})();
