// rpbench report.html: inflate the embedded Plotly bundle, draw every figure, set up the map.
// Nothing is fetched: the page works offline and copied alone.
"use strict";

(function () {
  const root = document.documentElement;
  const status = document.getElementById("rpbench-status");

  function fail(err) {
    root.dataset.rpbench = "error";
    if (!status.isConnected) document.querySelector("main").prepend(status);  // removed once the drawing began
    status.className = "error";
    status.textContent = "This page could not draw its figures: " + (err && err.message ? err.message : err);
    console.error(err);
  }

  // ---- the plotting library -----------------------------------------------------------------------
  // Inflated synchronously, while the page is parsed, so that every figure is drawn before the load event:
  // a headless screenshot, a print or a slow machine sees the figures, not a "loading" line.  The browser's
  // DecompressionStream is asynchronous, hence this small inflater (RFC 1951, after zlib's puff.c).
  const LEN_BASE = [3, 4, 5, 6, 7, 8, 9, 10, 11, 13, 15, 17, 19, 23, 27, 31, 35, 43, 51, 59, 67, 83, 99, 115, 131,
    163, 195, 227, 258];
  const LEN_EXTRA = [0, 0, 0, 0, 0, 0, 0, 0, 1, 1, 1, 1, 2, 2, 2, 2, 3, 3, 3, 3, 4, 4, 4, 4, 5, 5, 5, 5, 0];
  const DIST_BASE = [1, 2, 3, 4, 5, 7, 9, 13, 17, 25, 33, 49, 65, 97, 129, 193, 257, 385, 513, 769, 1025, 1537,
    2049, 3073, 4097, 6145, 8193, 12289, 16385, 24577];
  const DIST_EXTRA = [0, 0, 0, 0, 1, 1, 2, 2, 3, 3, 4, 4, 5, 5, 6, 6, 7, 7, 8, 8, 9, 9, 10, 10, 11, 11, 12, 12, 13, 13];
  const CLEN_ORDER = [16, 17, 18, 0, 8, 7, 9, 6, 10, 5, 11, 4, 12, 3, 13, 2, 14, 1, 15];

  // A canonical Huffman code as a lookup table: indexed by the next `max` bits of the stream (codes are
  // packed from their first bit on, hence reversed), each entry holds symbol << 4 | code length.
  function huffman(lengths) {
    let max = 0;
    for (const l of lengths) if (l > max) max = l;
    const count = new Uint16Array(16), next = new Uint16Array(16), table = new Int32Array(1 << max);
    for (const l of lengths) count[l]++;
    count[0] = 0;
    for (let l = 1, code = 0; l < 16; l++) { code = (code + count[l - 1]) << 1; next[l] = code; }
    for (let s = 0; s < lengths.length; s++) {
      const l = lengths[s];
      if (!l) continue;
      let code = next[l]++, rev = 0;
      for (let i = 0; i < l; i++) { rev = (rev << 1) | (code & 1); code >>= 1; }
      for (let i = rev; i < table.length; i += 1 << l) table[i] = (s << 4) | l;
    }
    return { table, max };
  }

  function gunzip(src) {
    const flags = src[3];
    if (src[0] !== 0x1f || src[1] !== 0x8b || src[2] !== 8) throw new Error("the embedded library is not gzip");
    let pos = 10;
    if (flags & 4) pos += 2 + (src[pos] | (src[pos + 1] << 8));
    for (const bit of [8, 16]) if (flags & bit) { while (src[pos++] !== 0); }
    if (flags & 2) pos += 2;
    const n = src.length, size = (src[n - 4] | (src[n - 3] << 8) | (src[n - 2] << 16) | (src[n - 1] << 24)) >>> 0;
    const out = new Uint8Array(size);
    let at = 0, buf = 0, cnt = 0;
    function fill(k) {
      while (cnt < k) {
        if (pos >= n) throw new Error("the embedded library is truncated");
        buf |= src[pos++] << cnt; cnt += 8;
      }
    }
    function bits(k) {
      fill(k);
      const v = buf & ((1 << k) - 1);
      buf >>>= k; cnt -= k;
      return v;
    }
    function decode(h) {
      if (cnt < h.max) fill(Math.min(h.max, cnt + 8 * (n - pos)));  // the stream's last code may be short
      const e = h.table[buf & ((1 << h.max) - 1)], l = e & 15;
      if (l === 0 || l > cnt) throw new Error("the embedded library is corrupt");
      buf >>>= l; cnt -= l;
      return e >> 4;
    }
    function codes(lit, dist) {
      for (;;) {
        let sym = decode(lit);
        if (sym < 256) { out[at++] = sym; continue; }
        if (sym === 256) return;
        sym -= 257;
        const len = LEN_BASE[sym] + bits(LEN_EXTRA[sym]);
        const d = decode(dist), back = DIST_BASE[d] + bits(DIST_EXTRA[d]);
        for (let i = 0; i < len; i++, at++) out[at] = out[at - back];
      }
    }
    function dynamic() {
      const nlen = bits(5) + 257, ndist = bits(5) + 1, ncode = bits(4) + 4;
      const cl = new Uint8Array(19);
      for (let i = 0; i < ncode; i++) cl[CLEN_ORDER[i]] = bits(3);
      const clh = huffman(cl), lengths = new Uint8Array(nlen + ndist);
      for (let i = 0; i < nlen + ndist; ) {
        const sym = decode(clh);
        if (sym < 16) { lengths[i++] = sym; continue; }
        const [value, repeat] = sym === 16 ? [lengths[i - 1], 3 + bits(2)] : sym === 17 ? [0, 3 + bits(3)] : [0, 11 + bits(7)];
        lengths.fill(value, i, i + repeat);
        i += repeat;
      }
      codes(huffman(lengths.subarray(0, nlen)), huffman(lengths.subarray(nlen)));
    }
    let last;
    do {
      last = bits(1);
      const type = bits(2);
      if (type === 0) {  // stored: whole bytes from the next byte boundary (give back the bytes read ahead)
        pos -= cnt >> 3; buf = 0; cnt = 0;
        const len = src[pos] | (src[pos + 1] << 8);
        out.set(src.subarray(pos + 4, pos + 4 + len), at);
        pos += 4 + len; at += len;
      } else if (type === 1) {
        codes(FIXED.lit, FIXED.dist);
      } else if (type === 2) {
        dynamic();
      } else {
        throw new Error("the embedded library is corrupt");
      }
    } while (!last);
    return out;
  }

  const FIXED = (function () {
    const lit = new Uint8Array(288);
    lit.fill(8, 0, 144); lit.fill(9, 144, 256); lit.fill(7, 256, 280); lit.fill(8, 280, 288);
    return { lit: huffman(lit), dist: huffman(new Uint8Array(30).fill(5)) };
  })();

  function loadPlotly() {
    const text = atob(document.getElementById("rpbench-plotly").textContent.trim());
    const bytes = new Uint8Array(text.length);
    for (let i = 0; i < text.length; i++) bytes[i] = text.charCodeAt(i);
    const script = document.createElement("script");
    const t0 = performance.now();
    script.textContent = new TextDecoder().decode(gunzip(bytes));
    root.dataset.inflateMs = String(Math.round(performance.now() - t0));
    document.head.appendChild(script);  // an inline script runs as it is inserted
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
    slider.value = String(m.first_window || 0);  // a short window: the whole period is a web of lines

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
  // Everything up to the drawing runs synchronously (see above); Plotly's promises only say when it is done.
  try {
    loadPlotly();
    const data = JSON.parse(document.getElementById("rpbench-data").textContent);
    const jobs = Object.entries(data.figures).map(([id, fig]) =>
      Plotly.newPlot(id, fig.data, fig.layout, data.config));
    if (data.map) jobs.push(setupMap(data.map, data.config));
    status.remove();
    Promise.all(jobs).then(() => {
      root.dataset.readyMs = String(Math.round(performance.now()));  // navigation start to every figure drawn
      root.dataset.rpbench = "ready";
    }, fail);
  } catch (err) {
    fail(err);
  }
})();
