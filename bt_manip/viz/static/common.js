// bt-manip viewer pages: the tree panel and the 3D view set-up shared by the live and replay pages.
"use strict";

const STATUS_NAMES = ["IDLE", "RUNNING", "SUCCESS", "FAILURE", "SKIPPED"];

class TreePanel {
  // nodes: [{i, name, id, depth, parent}]
  constructor(container, details, nodes) {
    this.nodes = nodes;
    this.details = details;
    this.rows = [];
    this.statuses = nodes.map(() => 0);
    this.reasons = nodes.map(() => "");
    this.selected = -1;
    this.failures = [];
    container.textContent = "";
    for (const n of nodes) {
      const row = document.createElement("div");
      row.className = "node";
      row.dataset.i = n.i;
      row.dataset.status = "IDLE";
      row.style.paddingLeft = (8 + 14 * n.depth) + "px";
      const chip = document.createElement("span");
      chip.className = "chip";
      const name = document.createElement("span");
      name.className = "name";
      name.textContent = n.name;
      const nid = document.createElement("span");
      nid.className = "nid";
      nid.textContent = n.id !== n.name ? n.id : "";
      const st = document.createElement("span");
      st.className = "st";
      st.textContent = "IDLE";
      row.append(chip, name, nid, st);
      row.addEventListener("mouseenter", () => this.showDetails(n.i));
      row.addEventListener("mouseleave", () => this.showDetails(this.selected));
      row.addEventListener("click", () => {
        this.selected = this.selected === n.i ? -1 : n.i;
        this.rows.forEach((r, k) => r.classList.toggle("selected", k === this.selected));
        this.showDetails(this.selected);
      });
      container.appendChild(row);
      this.rows.push(row);
    }
    this.showDetails(-1);
  }

  setStatus(i, code, reason) {
    this.statuses[i] = code;
    this.reasons[i] = reason || "";
    const row = this.rows[i];
    const name = STATUS_NAMES[code] || "IDLE";
    if (row.dataset.status !== name) {
      row.dataset.status = name;
      row.querySelector(".st").textContent = name;
    }
    row.title = reason ? name + ": " + reason : name;
  }

  setAll(statuses, reasons) {
    for (let i = 0; i < this.nodes.length; i++) this.setStatus(i, statuses[i], reasons[i]);
    this.showDetails(this.selected);
  }

  path(i) {
    const parts = [];
    for (let k = i; k >= 0; k = this.nodes[k].parent) parts.unshift(this.nodes[k].name);
    return parts.join("/");
  }

  showDetails(i) {
    const d = this.details;
    d.textContent = "";
    if (i >= 0) {
      const name = STATUS_NAMES[this.statuses[i]];
      d.textContent = this.path(i) + " [" + this.nodes[i].id + "]\n" + name +
        (this.reasons[i] ? ": " + this.reasons[i] : "");
      return;
    }
    const failed = this.failures.length ? this.failures :
      this.nodes.map((n, k) => [null, k, this.reasons[k]]).filter(
        ([, k, r]) => this.statuses[k] === 3 && r);
    if (!failed.length) {
      d.textContent = "Hover or click a node for its status and reason.";
      return;
    }
    const head = document.createElement("div");
    head.textContent = "Failures so far (latest first):";
    d.appendChild(head);
    for (const [t, k, reason] of failed.slice().reverse()) {
      const line = document.createElement("div");
      line.className = "fail";
      line.textContent = (t === null ? "" : formatTime(t) + "  ") + this.path(k) +
        (reason ? ": " + reason : "");
      d.appendChild(line);
    }
  }

  // counts: per node [ticks, success, failure, skipped, halted] over the whole run (the run
  // report's counts): each row gets a badge with its ticks, and rows never ticked are dimmed
  setCounts(counts) {
    this.counts = counts;
    counts.forEach((c, i) => {
      const row = this.rows[i];
      if (!row || !c) return;
      const badge = document.createElement("span");
      badge.className = "cov";
      badge.textContent = c[0] ? "\u00d7" + c[0] : "never ticked";
      badge.title = c[0] ? `ticked ${c[0]} times: ${c[1]} success, ${c[2]} failure, ` +
        `${c[3]} skipped, halted ${c[4]} times while running` : "never ticked in this run";
      row.insertBefore(badge, row.querySelector(".st"));
      row.classList.toggle("never", !c[0]);
    });
  }

  // failures: [[time, node index, reason]] in time order
  setFailures(failures) {
    this.failures = failures;
    this.showDetails(this.selected);
  }
}

function makeViewer(pane) {
  const viewer = new MeshCat.Viewer(pane);
  // size the 3D view by its own box, not the window (the page has side and bottom bars)
  viewer.set_3d_pane_size = function (w, h) {
    w = w === undefined ? pane.offsetWidth : w;
    h = h === undefined ? pane.offsetHeight : h;
    if (!w || !h) return;
    this.camera.aspect = w / h;
    this.camera.updateProjectionMatrix();
    this.renderer.setSize(w, h);
    this.set_dirty();
  };
  viewer.set_3d_pane_size();
  return viewer;
}

function formatTime(t) {
  return t.toFixed(2) + " s";
}
