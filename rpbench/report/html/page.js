// rpbench report.html: inflate the embedded Plotly bundle, draw every figure, set up the map.
// Nothing is fetched: the page works offline and copied alone.
"use strict";

(function () {
  const root = document.documentElement;
  const status = document.getElementById("rpbench-status");

  function fail(err) {
    root.dataset.rpbench = "error";
    status.className = "error";
    status.textContent = "This page could not draw its figures: " + (err && err.message ? err.message : err);
    console.error(err);
  }

  async function loadPlotly() {
    if (typeof DecompressionStream === "undefined") {
      throw new Error("this browser has no DecompressionStream (Chromium 80+, Firefox 113+, Safari 16.4+ have it)");
    }
    const text = atob(document.getElementById("rpbench-plotly").textContent.trim());
    const bytes = new Uint8Array(text.length);
    for (let i = 0; i < text.length; i++) bytes[i] = text.charCodeAt(i);
    const stream = new Blob([bytes]).stream().pipeThrough(new DecompressionStream("gzip"));
    const source = await new Response(stream).text();
    const script = document.createElement("script");
    script.textContent = source;
    document.head.appendChild(script);
    if (typeof window.Plotly === "undefined") throw new Error("the plotting library did not load");
  }

  // ---- the map ---------------------------------------------------------------------------------
  // One figure, fixed traces: roads, density, then per layer its lines and markers.  The run selector,
  // the layer boxes and the time window decide what the traces hold.
  const LAYERS = ["pooled", "solo", "cancelled"];

  function clock(m, t) {
    const s = Math.round(m.period.start_clock_s + t);
    const hh = Math.floor(s / 3600) % 24, mm = Math.floor(s / 60) % 60, ss = s % 60;
    const two = (x) => String(x).padStart(2, "0");
    return two(hh) + ":" + two(mm) + (m.period.seconds ? ":" + two(ss) : "");
  }

  function setupMap(m, config) {
    const div = document.getElementById("map-plot");
    const lon = m.nodes.lon, lat = m.nodes.lat;
    const runSelect = document.getElementById("map-run");
    const slider = document.getElementById("map-window");
    const play = document.getElementById("map-play");
    const note = document.getElementById("map-note");
    const boxes = {};
    for (const name of ["roads", "density", ...LAYERS]) boxes[name] = document.getElementById("map-show-" + name);

    const roads = { x: [], y: [] };
    for (let i = 0; i < m.edges.length; i += 2) {
      const a = m.edges[i], b = m.edges[i + 1];
      roads.x.push(lon[a], lon[b], null);
      roads.y.push(lat[a], lat[b], null);
    }
    const nWindows = Math.max(1, Math.ceil((m.period.end_s - m.period.begin_s) / m.period.window_s));
    slider.max = String(nWindows);

    function windowOf() {
      const k = Number(slider.value);
      if (k === 0) return [-Infinity, Infinity, "the whole period"];
      const a = m.period.begin_s + (k - 1) * m.period.window_s, b = a + m.period.window_s;
      return [a, b, clock(m, a) + "–" + clock(m, b)];
    }

    // items of one layer of one run within [a, b): their indices, and every `stride`-th of them drawn
    function pick(layer, a, b) {
      const idx = [];
      for (let i = 0; i < layer.t.length; i++) if (layer.t[i] >= a && layer.t[i] < b) idx.push(i);
      const stride = Math.max(1, Math.ceil(idx.length / m.max_drawn));
      return { all: idx, drawn: stride === 1 ? idx : idx.filter((_, j) => j % stride === 0), stride };
    }

    function traces() {
      const run = m.runs[Number(runSelect.value)];
      const [a, b, label] = windowOf();
      const state = { run: run.name, window: label, layers: {} };
      const out = [];
      out.push({ type: "scatter", mode: "lines", name: "roads", x: roads.x, y: roads.y, hoverinfo: "skip",
                 line: { color: "#c3c8d2", width: 0.7 }, visible: boxes.roads.checked, showlegend: false });
      const dens = { x: [], y: [] };
      const sentences = [];
      const per = {};
      for (const name of LAYERS) {
        const layer = run[name];
        const p = pick(layer, a, b);
        per[name] = p;
        state.layers[name] = { in_window: p.all.length, drawn: p.drawn.length, stride: p.stride };
        if (boxes[name].checked) {
          const k = layer.stops;  // stops per item: 4 (pooled), 2 (solo), 1 (cancelled)
          for (const i of p.all) { dens.x.push(lon[layer.nodes[i * k]]); dens.y.push(lat[layer.nodes[i * k]]); }
          let s = p.all.length.toLocaleString("en") + " " + m.layer_names[name];
          if (p.stride > 1) s += " (drawn: 1 in " + p.stride + ", " + p.drawn.length.toLocaleString("en") + ")";
          sentences.push(s);
        }
      }
      out.push({ type: "histogram2d", name: "density", x: dens.x, y: dens.y, nbinsx: 70, nbinsy: 70,
                 colorscale: [[0, "rgba(255,255,255,0)"], [1e-9, "rgba(255,224,130,0.55)"], [0.35, "rgba(244,109,67,0.7)"],
                              [1, "rgba(165,0,38,0.85)"]], zmin: 0, showscale: false, visible: boxes.density.checked,
                 hovertemplate: "%{z} items<extra>density</extra>" });
      // pooled pairs: the path through the four stops, the first pick-up, the join (second pick-up), drop-offs
      const pooled = run.pooled, P = per.pooled.drawn, show = boxes.pooled.checked;
      const path = { x: [], y: [] }, first = { x: [], y: [], text: [] }, join = { x: [], y: [], text: [] },
            drop = { x: [], y: [], text: [] };
      for (const i of P) {
        const n = pooled.nodes.slice(4 * i, 4 * i + 4), who = "orders " + pooled.orders[2 * i] + " + " + pooled.orders[2 * i + 1];
        for (const v of n) { path.x.push(lon[v]); path.y.push(lat[v]); }
        path.x.push(null); path.y.push(null);
        first.x.push(lon[n[0]]); first.y.push(lat[n[0]]); first.text.push(who + ", first pick-up " + clock(m, pooled.t[i]));
        join.x.push(lon[n[1]]); join.y.push(lat[n[1]]); join.text.push(who + ", join (second pick-up)");
        for (const v of [n[2], n[3]]) { drop.x.push(lon[v]); drop.y.push(lat[v]); drop.text.push(who + ", drop-off"); }
      }
      const color = run.color || "#2ca02c";
      out.push({ type: "scatter", mode: "lines", name: "pooled: route", x: path.x, y: path.y, hoverinfo: "skip",
                 line: { color: color, width: 1.2 }, opacity: 0.55, visible: show, legendgroup: "pooled" });
      out.push({ type: "scatter", mode: "markers", name: "pooled: first pick-up", x: first.x, y: first.y, text: first.text,
                 hovertemplate: "%{text}<extra></extra>", marker: { color: color, size: 7, symbol: "circle" },
                 visible: show, legendgroup: "pooled", meta: { layer: "pooled", role: "first_pickup" } });
      out.push({ type: "scatter", mode: "markers", name: "pooled: join", x: join.x, y: join.y, text: join.text,
                 hovertemplate: "%{text}<extra></extra>", marker: { color: color, size: 7, symbol: "diamond-open", line: { width: 2 } },
                 visible: show, legendgroup: "pooled" });
      out.push({ type: "scatter", mode: "markers", name: "pooled: drop-off", x: drop.x, y: drop.y, text: drop.text,
                 hovertemplate: "%{text}<extra></extra>", marker: { color: color, size: 6, symbol: "x-thin-open", line: { width: 2, color: color } },
                 visible: show, legendgroup: "pooled" });
      // solo trips: pick-up to drop-off
      const solo = run.solo, S = per.solo.drawn, soloPath = { x: [], y: [] }, soloPick = { x: [], y: [], text: [] };
      for (const i of S) {
        const p = solo.nodes[2 * i], d = solo.nodes[2 * i + 1];
        soloPath.x.push(lon[p], lon[d], null); soloPath.y.push(lat[p], lat[d], null);
        soloPick.x.push(lon[p]); soloPick.y.push(lat[p]);
        soloPick.text.push("order " + solo.orders[i] + ", solo, picked up " + clock(m, solo.t[i]));
      }
      out.push({ type: "scatter", mode: "lines", name: "solo: trip", x: soloPath.x, y: soloPath.y, hoverinfo: "skip",
                 line: { color: "#6f7b91", width: 1 }, opacity: 0.6, visible: boxes.solo.checked, legendgroup: "solo" });
      out.push({ type: "scatter", mode: "markers", name: "solo: pick-up", x: soloPick.x, y: soloPick.y, text: soloPick.text,
                 hovertemplate: "%{text}<extra></extra>", marker: { color: "#6f7b91", size: 5 },
                 visible: boxes.solo.checked, legendgroup: "solo", meta: { layer: "solo" } });
      const canc = run.cancelled, C = per.cancelled.drawn, cx = [], cy = [], ct = [];
      for (const i of C) {
        cx.push(lon[canc.nodes[i]]); cy.push(lat[canc.nodes[i]]);
        ct.push("order " + canc.orders[i] + ", cancelled " + clock(m, canc.t[i]));
      }
      out.push({ type: "scatter", mode: "markers", name: "cancelled request", x: cx, y: cy, text: ct,
                 hovertemplate: "%{text}<extra></extra>", marker: { color: "#d62728", size: 7, symbol: "x" },
                 visible: boxes.cancelled.checked, meta: { layer: "cancelled" } });
      note.textContent = run.label + ", " + label + ": " + (sentences.length ? sentences.join("; ") : "no layer selected") + ".";
      state.shown = out.filter((t) => t.visible).map((t) => t.name);
      window.rpbenchMap = state;
      return out;
    }

    const layout = Object.assign({}, m.layout);
    function redraw() { return Plotly.react(div, traces(), layout, config); }
    for (const el of [runSelect, slider, ...Object.values(boxes)]) el.addEventListener("input", redraw);
    let timer = null;
    play.addEventListener("click", () => {
      if (timer) { clearInterval(timer); timer = null; play.textContent = "Play"; return; }
      play.textContent = "Pause";
      timer = setInterval(() => {
        slider.value = String((Number(slider.value) % nWindows) + 1);
        redraw();
      }, 900);
    });
    return redraw();
  }

  // ---- boot ------------------------------------------------------------------------------------
  (async function () {
    try {
      await loadPlotly();
      const data = JSON.parse(document.getElementById("rpbench-data").textContent);
      const jobs = Object.entries(data.figures).map(([id, fig]) =>
        Plotly.newPlot(id, fig.data, fig.layout, data.config));
      if (data.map) jobs.push(setupMap(data.map, data.config));
      await Promise.all(jobs);
      status.remove();
      root.dataset.readyMs = String(Math.round(performance.now()));  // navigation start to every figure drawn
      root.dataset.rpbench = "ready";
    } catch (err) {
      fail(err);
    }
  })();
})();
