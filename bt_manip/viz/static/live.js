// bt-manip live page: the meshcat server's own view in a frame, tree statuses polled.
"use strict";

(function () {
  const config = JSON.parse(document.getElementById("bt-config").textContent);
  const clock = document.getElementById("clock");
  const result = document.getElementById("result");
  let panel = null;
  let version = -1;
  window.btPage = { updates: 0, ended: false };

  async function loadTree() {
    const res = await fetch("tree.json", { cache: "no-store" });
    const data = await res.json();
    panel = new TreePanel(document.getElementById("tree"), document.getElementById("details"), data.nodes);
    document.getElementById("title").textContent = data.title;
  }

  async function poll() {
    try {
      if (!panel) await loadTree();
      const res = await fetch("state.json?since=" + version, { cache: "no-store" });
      const s = await res.json();
      if (s.version !== version) {
        version = s.version;
        panel.setAll(s.statuses, s.reasons);
        panel.setFailures(s.failures || []);
        clock.textContent = formatTime(s.time) + " \u00b7 tick " + s.ticks;
        result.textContent = s.result ? "result: " + s.result : "";
        window.btPage.updates++;
      }
    } catch (e) {
      result.textContent += " (run ended)";
      window.btPage.ended = true;
      return;
    }
    setTimeout(poll, config.poll_ms || 200);
  }
  poll();
})();
