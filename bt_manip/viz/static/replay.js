// bt-manip replay page: unpack the embedded recording and play it on a timeline.
"use strict";

(async function () {
  const notice = document.getElementById("notice");
  function fail(message) {
    notice.textContent = message;
    notice.style.display = "block";
    window.btReplay = { error: message };
  }
  if (typeof DecompressionStream === "undefined") {
    fail("This browser cannot unpack the replay (no DecompressionStream).");
    return;
  }

  // -- unpack ---------------------------------------------------------------------------------
  const text = document.getElementById("bt-replay").textContent.trim();
  const bin = atob(text);
  const packed = new Uint8Array(bin.length);
  for (let i = 0; i < bin.length; i++) packed[i] = bin.charCodeAt(i);
  const stream = new Blob([packed]).stream().pipeThrough(new DecompressionStream("gzip"));
  const data = await new Response(stream).arrayBuffer();
  const view = new DataView(data);
  const magic = String.fromCharCode(view.getUint8(0), view.getUint8(1), view.getUint8(2), view.getUint8(3));
  if (magic !== "BTRP") {
    fail("The replay data is damaged.");
    return;
  }
  const headLength = view.getUint32(4, true);
  const header = JSON.parse(new TextDecoder().decode(new Uint8Array(data, 8, headLength)));
  const base = 8 + headLength;
  const bytes = (ref) => new Uint8Array(data.slice(base + ref.offset, base + ref.offset + ref.length));
  const floats = (ref) => new Float32Array(data.slice(base + ref.offset, base + ref.offset + ref.length));
  const split = (p) => p.split("/").filter((x) => x.length > 0);

  // -- scene ----------------------------------------------------------------------------------
  const pane = document.getElementById("meshcat-pane");
  const viewer = makeViewer(pane);
  const scene = header.scene;
  const meshes = scene.meshes.map((m) =>
    m.format === "stl" ? { stl: true, ref: m } : { text: new TextDecoder().decode(bytes(m)) });
  function meshData(ref) {
    const m = meshes[ref.$mesh];
    return m.stl ? bytes(m.ref) : m.text;
  }
  for (const obj of scene.objects) {
    const json = obj.json;
    if (json.object.data && json.object.data.$mesh !== undefined) json.object.data = meshData(json.object.data);
    for (const g of json.geometries) {
      if (g.data && g.data.$mesh !== undefined) g.data = meshData(g.data);
    }
    viewer.handle_command({ type: "set_object", path: obj.path, object: json });
  }
  for (const [path, m] of scene.static) viewer.set_transform(split(path), m);

  const n = header.frames.count;
  const times = floats(header.frames.times);
  // each track has samples for frames first .. first + count - 1 (its body's time in the world)
  const tracks = scene.tracks.map((t) => ({
    node: viewer.scene_tree.find(split(t.path)).object,
    path: t.path,
    constant: t.const,
    first: t.first,
    count: t.count,
    values: floats(t),
  }));
  // bodies spawned or deleted while the run went on are shown only while they were there
  const bodies = scene.bodies.map((b) => ({
    name: b.name,
    node: viewer.scene_tree.find(split(b.path)).object,
    appear: b.appear,
    disappear: b.disappear,
  }));
  const duration = header.duration;

  // the orbit controls look at the origin: shift the drawing so the robot is there
  const camera = scene.camera;
  const drawing = viewer.scene_tree.find(split(header.root).slice(0, 1)).object;
  const followTrack = tracks.find((t) => t.path === camera.follow);
  // and down by the look height, the floor grid and the axes with it
  const lookHeight = camera.target[2] || 0;
  for (const helper of ["Grid", "Axes"]) viewer.scene_tree.find([helper]).object.position.set(0, 0, -lookHeight);
  function centreOn(x, y) {
    drawing.position.set(-x, -y, -lookHeight);
  }
  centreOn(camera.target[0], camera.target[1]);
  const off = camera.offset;
  viewer.set_property(["Cameras", "default", "rotated", "<object>"], "position", [off[0], off[2], -off[1]]);

  // -- tree -----------------------------------------------------------------------------------
  const tree = header.tree;
  const panel = new TreePanel(document.getElementById("tree"), document.getElementById("details"), tree.nodes);
  if (tree.counts) panel.setCounts(tree.counts);
  const reasons = tree.reasons;
  const events = tree.events;
  const statuses = tree.nodes.map(() => 0);
  const why = tree.nodes.map(() => "");
  let applied = 0; // events[0 .. applied) are in effect

  // -- overlays and highlights ------------------------------------------------------------------
  const overlayRoot = "/meshcat/bt_manip_overlay";
  let overlayApplied = 0;
  let highlightApplied = 0;
  const HIGHLIGHT = [0.15, 0.95, 0.55, 1.0];

  function resetExtras() {
    viewer.handle_command({ type: "delete", path: overlayRoot });
    overlayApplied = 0;
    for (const body of Object.keys(scene.body_objects)) setHighlight(body, false);
    highlightApplied = 0;
  }
  function setHighlight(body, on) {
    for (const [path, rgba] of scene.body_objects[body] || []) {
      viewer.set_property(split(path), "color", on ? HIGHLIGHT : rgba);
    }
  }
  function applyExtras(t) {
    while (overlayApplied < header.overlay.length && header.overlay[overlayApplied][0] <= t + 1e-9) {
      const [, name, obj, m] = header.overlay[overlayApplied++];
      const path = overlayRoot + "/" + name;
      if (obj === null && m === null) {
        viewer.handle_command({ type: "delete", path: path });
        continue;
      }
      if (obj !== null) viewer.handle_command({ type: "set_object", path: path, object: JSON.parse(JSON.stringify(obj)) });
      viewer.set_transform(split(path), m || [1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1]);
    }
    while (highlightApplied < header.highlights.length && header.highlights[highlightApplied][0] <= t + 1e-9) {
      const [, body, on] = header.highlights[highlightApplied++];
      setHighlight(body, on);
    }
  }

  // -- time -----------------------------------------------------------------------------------
  function frameAt(t) {
    let lo = 0, hi = n - 1;
    if (n === 0) return -1;
    while (lo < hi) {
      const mid = (lo + hi + 1) >> 1;
      if (times[mid] <= t + 1e-6) lo = mid; else hi = mid - 1;
    }
    return lo;
  }
  function present(b, t) {
    return b.appear <= t + 1e-6 && (b.disappear === null || t < b.disappear - 1e-6);
  }
  function setFrame(k, t) {
    if (k < 0) return;
    for (const b of bodies) b.node.visible = present(b, t);
    for (const tr of tracks) {
      const v = tr.values;
      if (tr.constant) {
        tr.node.position.set(v[0], v[1], v[2]);
        tr.node.quaternion.set(v[3], v[4], v[5], v[6]);
      } else {
        const c = tr.count;
        const j = Math.max(0, Math.min(c - 1, k - tr.first));
        tr.node.position.set(v[j], v[c + j], v[2 * c + j]);
        tr.node.quaternion.set(v[3 * c + j], v[4 * c + j], v[5 * c + j], v[6 * c + j]);
      }
    }
    if (follow.checked && followTrack) centreOn(followTrack.node.position.x, followTrack.node.position.y);
  }
  // where a body is in the world at time t (for tests and tools): [x, y, z] or null when absent
  function bodyPosition(name, t) {
    const b = bodies.find((x) => x.name === name);
    if (!b || !present(b, t)) return null;
    const tr = tracks.find((x) => x.path === header.root + "/" + name);
    if (!tr) return null;
    const k = frameAt(t);
    const v = tr.values;
    if (tr.constant) return [v[0], v[1], v[2]];
    const c = tr.count;
    const j = Math.max(0, Math.min(c - 1, k - tr.first));
    return [v[j], v[c + j], v[2 * c + j]];
  }
  let current = -1;
  function seek(t) {
    t = Math.max(0, Math.min(duration, t));
    if (t < current) {
      for (let i = 0; i < statuses.length; i++) { statuses[i] = 0; why[i] = ""; }
      applied = 0;
      resetExtras();
    }
    const before = applied;
    while (applied < events.length && events[applied][0] <= t + 1e-9) {
      const [, i, code, r] = events[applied++];
      statuses[i] = code;
      why[i] = reasons[r];
    }
    applyExtras(t);
    panel.setAll(statuses, why);
    if (applied !== before || t < current) {
      const failures = [];
      for (let k = 0; k < applied; k++) {
        if (events[k][2] === 3) failures.push([events[k][0], events[k][1], reasons[events[k][3]]]);
      }
      panel.setFailures(failures.slice(-12));
    }
    setFrame(frameAt(t), t);
    current = t;
    seekBar.value = t;
    label.textContent = formatTime(t) + " / " + formatTime(duration);
    clock.textContent = formatTime(t);
    result.textContent = t >= duration && header.result ? "result: " + header.result : "";
    viewer.set_dirty();
  }

  const seekBar = document.getElementById("seek");
  const label = document.getElementById("tlabel");
  const clock = document.getElementById("clock");
  const result = document.getElementById("result");
  const playButton = document.getElementById("play");
  const speed = document.getElementById("speed");
  const follow = document.getElementById("follow");
  follow.checked = !!followTrack;
  follow.addEventListener("change", () => seek(current));
  seekBar.max = duration;
  seekBar.step = Math.max(0.001, duration / 2000);
  let playing = false;
  let last = 0;
  function frame(now) {
    if (!playing) return;
    const dt = (now - last) / 1000;
    last = now;
    seek(current + dt * parseFloat(speed.value));
    if (current >= duration) { setPlaying(false); return; }
    requestAnimationFrame(frame);
  }
  function setPlaying(on) {
    playing = on;
    playButton.innerHTML = on ? "&#10073;&#10073;" : "&#9654;";
    if (on) {
      if (current >= duration) seek(0);
      last = performance.now();
      requestAnimationFrame(frame);
    }
  }
  playButton.addEventListener("click", () => setPlaying(!playing));
  seekBar.addEventListener("input", () => { setPlaying(false); seek(parseFloat(seekBar.value)); });
  document.addEventListener("keydown", (e) => {
    if (e.code === "Space" && e.target === document.body) { e.preventDefault(); setPlaying(!playing); }
  });

  // root status along the timeline
  const strip = document.getElementById("strip");
  function drawStrip() {
    strip.width = strip.clientWidth || 800;
    const ctx = strip.getContext("2d");
    const colours = ["#6b6e78", "#f0b429", "#2fb344", "#e03131", "#4c6ef5"];
    let code = 0, from = 0;
    const w = strip.width;
    const span = duration > 0 ? duration : 1;
    for (const [t, i, c] of events.concat([[duration, 0, -1]])) {
      if (i !== 0) continue;
      ctx.fillStyle = colours[code];
      ctx.fillRect((from / span) * w, 0, Math.max(1, ((t - from) / span) * w), strip.height);
      code = c; from = t;
    }
  }
  strip.style.width = "100%";
  drawStrip();
  window.addEventListener("resize", drawStrip);

  document.getElementById("title").textContent = header.title;
  seek(0);
  window.btReplay = {
    duration: duration,
    frames: n,
    seek: (t) => { setPlaying(false); seek(t); },
    play: () => setPlaying(true),
    time: () => current,
    statuses: () => statuses.slice(),
    bodies: () => bodies.map((b) => ({ name: b.name, appear: b.appear, disappear: b.disappear })),
    visible: (name) => { const b = bodies.find((x) => x.name === name); return !!b && b.node.visible; },
    bodyPosition: bodyPosition,
    frameTimes: () => Array.from(times),
    viewer: viewer,
  };
})();
