/* flexshaft's mode viewer: a drivetrain's surface animated through one period of a mode.
 *
 * Data (one JSON object per viewer, written by flexshaft.views.webview): the undeformed surface
 * (points in m, triangles, generator lines), per mode the normalised twist of every point (largest
 * station rotation 1), its shear stress and strain-energy density at the stated amplitude, and
 * the lateral motion of a 6-DOF mode. Each frame turns every point about the shaft axis by
 * sin(2πt/T)·A·φ (A the visual twist, T the animation's period) and colours it by the quantity at
 * that instant. Needs window.FS3 (three.js, three-fs3.min.js). Nothing is fetched.
 */
(function () {
  'use strict';

  const PERIOD_S = 2.0; // one period of the mode drawn in 2 s
  // Diverging (signed quantities) and sequential (energy) colour maps, as RGB stops 0..1.
  const DIVERGING = [[59, 76, 192], [98, 130, 234], [141, 176, 254], [184, 208, 249], [221, 221, 221],
    [245, 196, 173], [244, 154, 123], [222, 96, 77], [180, 4, 38]];
  const SEQUENTIAL = [[240, 240, 240], [254, 224, 144], [253, 174, 97], [244, 109, 67], [215, 48, 39],
    [165, 0, 38]];

  function decode(b64, Type) {
    const bin = atob(b64);
    const bytes = new Uint8Array(bin.length);
    for (let i = 0; i < bin.length; i++) bytes[i] = bin.charCodeAt(i);
    return new Type(bytes.buffer);
  }

  // An array sent as int16 fractions of its largest magnitude: back to floats in its unit.
  function dequantise(q) {
    const raw = decode(q.data, Int16Array);
    const out = new Float32Array(raw.length);
    const f = q.max / 32767;
    for (let i = 0; i < raw.length; i++) out[i] = raw[i] * f;
    return out;
  }

  // Points sent as int16 steps across their bounding box, per axis: back to metres.
  function ungrid(g) {
    const q = decode(g.data, Int16Array);
    const out = new Float32Array(q.length);
    for (let i = 0; i < q.length; i++) {
      const a = i % 3;
      out[i] = g.lo[a] + (q[i] + 32767) / 65534 * (g.hi[a] - g.lo[a]);
    }
    return out;
  }

  function mapColour(stops, u, out, k) {
    const x = Math.min(Math.max(u, 0), 1) * (stops.length - 1);
    const i = Math.min(Math.floor(x), stops.length - 2);
    const w = x - i;
    for (let c = 0; c < 3; c++) out[k + c] = ((1 - w) * stops[i][c] + w * stops[i + 1][c]) / 255;
  }

  // Round ticks (1, 2, 5 times a power of ten) covering [lo, hi].
  function niceTicks(lo, hi, count) {
    const span = hi - lo;
    if (!(span > 0)) return [lo];
    const raw = span / Math.max(count, 1);
    const p = Math.pow(10, Math.floor(Math.log10(raw)));
    const step = [1, 2, 5, 10].map((m) => m * p).find((s) => s >= raw);
    const ticks = [];
    for (let v = Math.ceil(lo / step) * step; v <= hi + 1e-9 * span; v += step) {
      ticks.push(Math.abs(v) < 1e-12 * span ? 0 : v);
    }
    return ticks;
  }

  function fmt(v) {
    const a = Math.abs(v);
    if (a === 0) return '0';
    if (a >= 1e4 || a < 1e-4) return v.toExponential(1).replace('e+', 'e');
    return String(+v.toPrecision(3));
  }

  function niceLength(x) {
    const p = Math.pow(10, Math.floor(Math.log10(x)));
    return [5, 2, 1].map((m) => m * p).find((s) => s <= x) || p;
  }

  function el(tag, attrs, parent) {
    const e = document.createElement(tag);
    for (const [k, v] of Object.entries(attrs || {})) {
      if (k === 'text') e.textContent = v; else if (k === 'style') e.style.cssText = v; else e.setAttribute(k, v);
    }
    if (parent) parent.appendChild(e);
    return e;
  }

  function Viewer(root, data) {
    const T = window.FS3;
    this.data = data;
    const n = data.n_points;
    this.base = ungrid(data.points);
    const index = data.index_type === 'u16' ? decode(data.triangles, Uint16Array) : decode(data.triangles, Uint32Array);
    const lines = data.index_type === 'u16' ? decode(data.lines, Uint16Array) : decode(data.lines, Uint32Array);
    this.modes = data.modes.map((m) => ({
      meta: m,
      phi: dequantise(m.phi),
      stress: dequantise(m.stress),
      energy: dequantise(m.energy),
      lateral: m.lateral ? dequantise(m.lateral) : null,
    }));
    this.mode = Math.min(data.initial || 0, data.modes.length - 1);
    this.colour = data.colour || 'twist';
    this.amplitude = data.scale; // visual twist of the largest station rotation, rad
    // "#t=1.5" in the page's address starts the animation 1.5 s into its period (a fixed moment to look
    // at, or to screenshot)
    const at = /(?:^#|&)t=([0-9.]+)/.exec(window.location.hash || '');
    this.clock = at ? parseFloat(at[1]) : 0;
    // "#t=0.5&paused": that moment, held (a still of the viewer)
    const held = /(?:^#|&)paused(?:&|$)/.test(window.location.hash || '');
    this.last = null;

    // --- the page: toolbar, drawing area with labels and overlays, caption --------------------------
    root.classList.add('fs-viewer');
    this.playing = !held;
    const bar = el('div', { class: 'fs-bar' }, root);
    this.modeSelect = el('select', { 'aria-label': 'mode' }, bar);
    data.modes.forEach((m, k) => el('option', { value: k, text: `mode ${m.index}: ${fmt(m.frequency_hz)} Hz` }, this.modeSelect));
    this.modeSelect.value = String(this.mode);
    if (data.modes.length < 2) this.modeSelect.disabled = true;
    this.playButton = el('button', { type: 'button', text: this.playing ? 'pause' : 'play' }, bar);
    el('label', { text: 'twist drawn' }, bar);
    this.ampInput = el('input', { type: 'range', min: '1', max: '90', step: '1', value: String(Math.round(this.amplitude * 180 / Math.PI)), 'aria-label': 'twist drawn, degrees' }, bar);
    this.ampText = el('span', {}, bar);
    this.colourSelect = el('select', { 'aria-label': 'colour' }, bar);
    for (const c of ['twist', 'stress', 'energy']) el('option', { value: c, text: `colour: ${c}` }, this.colourSelect);
    this.colourSelect.value = this.colour;
    const reset = el('button', { type: 'button', text: 'reset view' }, bar);

    const stage = el('div', { class: 'fs-stage' }, root);
    const width = Math.max(stage.clientWidth || 900, 300);
    const height = Math.round(width * 0.5);
    stage.style.height = height + 'px';
    const renderer = new T.WebGLRenderer({ antialias: true, preserveDrawingBuffer: true });
    renderer.setPixelRatio(window.devicePixelRatio || 1);
    renderer.setSize(width, height);
    stage.appendChild(renderer.domElement);
    this.overlay = el('div', { class: 'fs-labels' }, stage);
    this.svg = document.createElementNS('http://www.w3.org/2000/svg', 'svg');
    this.svg.setAttribute('class', 'fs-leaders');
    this.svg.setAttribute('width', width);
    this.svg.setAttribute('height', height);
    stage.appendChild(this.svg);
    this.colourbar = el('canvas', { class: 'fs-colourbar', width: '90', height: String(Math.min(260, height - 40)) }, stage);
    this.triad = el('canvas', { class: 'fs-triad', width: '90', height: '90' }, stage);
    this.scalebar = el('div', { class: 'fs-scale' }, stage);
    this.caption = el('p', { class: 'fs-caption' }, root);
    this.width = width;
    this.height = height;
    this.renderer = renderer;

    // --- the scene: surface, generator lines, the undeformed ghost, discs -----------------------------
    const scene = new T.Scene();
    scene.background = new T.Color(0xffffff);
    this.scene = scene;
    const geometry = new T.BufferGeometry();
    this.positions = new Float32Array(this.base);
    this.colours = new Float32Array(3 * n);
    geometry.setAttribute('position', new T.BufferAttribute(this.positions, 3));
    geometry.setAttribute('color', new T.BufferAttribute(this.colours, 3));
    geometry.setIndex(new T.BufferAttribute(index, 1));
    this.geometry = geometry;
    scene.add(new T.Mesh(geometry, new T.MeshPhongMaterial({ vertexColors: true, side: T.DoubleSide, shininess: 20 })));
    const lineGeometry = new T.BufferGeometry();
    lineGeometry.setAttribute('position', geometry.getAttribute('position'));
    lineGeometry.setIndex(new T.BufferAttribute(lines, 1));
    scene.add(new T.LineSegments(lineGeometry, new T.LineBasicMaterial({ color: 0x202020 })));
    const ghostGeometry = new T.BufferGeometry();
    ghostGeometry.setAttribute('position', new T.BufferAttribute(this.base, 3));
    ghostGeometry.setIndex(new T.BufferAttribute(lines, 1));
    scene.add(new T.LineSegments(ghostGeometry, new T.LineBasicMaterial({ color: 0xb0b0b0, transparent: true, opacity: 0.6 })));
    this.discs = data.discs.map((d) => {
      const group = new T.Group();
      const disc = new T.Mesh(new T.CylinderGeometry(d.radius, d.radius, d.thickness, 48), new T.MeshPhongMaterial({ color: 0xcfcfcf }));
      disc.rotation.z = Math.PI / 2; // cylinder axis from y to x
      disc.position.x = d.x;
      group.add(disc);
      // a radius drawn on the disc's face: a rigid inertia turns as a whole
      const mark = new T.BufferGeometry();
      const xf = d.x + 0.51 * d.thickness;
      mark.setAttribute('position', new T.BufferAttribute(new Float32Array([xf, 0, 0, xf, 0, d.radius, xf, 0, 0, xf, d.radius, 0]), 3));
      group.add(new T.LineSegments(mark, new T.LineBasicMaterial({ color: 0x202020 })));
      scene.add(group);
      return { group, data: d };
    });
    // A hand at each station (two arms, +y and +z, as thin rods) turning with its twist, beside its
    // grey resting place: the twist seen however slender the shaft (see webview.HAND_LENGTH).
    this.hands = (data.hands || []).map((h) => {
      const group = new T.Group();
      const rest = new T.Group();
      const w = 0.02 * h.length;
      for (const [target, colour] of [[group, 0x1a1a1a], [rest, 0xb0b0b0]]) {
        for (const axis of ['y', 'z']) {
          const rod = new T.Mesh(new T.CylinderGeometry(w, w, h.length, 8), new T.MeshPhongMaterial({ color: colour }));
          if (axis === 'z') { rod.rotation.x = Math.PI / 2; rod.position.z = h.length / 2; } else { rod.position.y = h.length / 2; }
          target.add(rod);
        }
        target.position.x = h.x;
        scene.add(target);
      }
      return { group, data: h };
    });
    scene.add(new T.AmbientLight(0xffffff, 1.6));
    const light = new T.DirectionalLight(0xffffff, 1.6);
    light.position.set(0.3, -1, 1.2);
    scene.add(light);

    // --- camera: orthographic (a length scale holds everywhere), fitted to the drivetrain ---------------
    const box = data.bounds; // [[xmin, ymin, zmin], [xmax, ymax, zmax]]
    this.centre = new T.Vector3((box[0][0] + box[1][0]) / 2, (box[0][1] + box[1][1]) / 2, (box[0][2] + box[1][2]) / 2);
    this.size = new T.Vector3(box[1][0] - box[0][0], box[1][1] - box[0][1], box[1][2] - box[0][2]);
    const span = Math.max(this.size.x, this.size.y, this.size.z);
    this.camera = new T.OrthographicCamera(-1, 1, 1, -1, -10 * span, 10 * span);
    this.camera.up.set(0, 0, 1);
    this.controls = new T.OrbitControls(this.camera, renderer.domElement);
    this.controls.enableDamping = false;
    this.controls.addEventListener('change', () => { this.placeLabels(); this.drawTriad(); this.drawScale(); });
    this.fit();

    // --- wiring -------------------------------------------------------------------------------------------
    this.modeSelect.addEventListener('change', () => { this.mode = +this.modeSelect.value; this.update(); });
    this.colourSelect.addEventListener('change', () => { this.colour = this.colourSelect.value; this.update(); });
    this.ampInput.addEventListener('input', () => { this.amplitude = (+this.ampInput.value) * Math.PI / 180; this.update(); });
    this.playButton.addEventListener('click', () => {
      this.playing = !this.playing;
      this.playButton.textContent = this.playing ? 'pause' : 'play';
    });
    reset.addEventListener('click', () => this.fit());
    this.makeLabels();
    this.placeLabels();
    this.update();
    const tick = (now) => {
      if (this.last !== null && this.playing) this.clock += (now - this.last) / 1000;
      this.last = now;
      this.frame(Math.sin(2 * Math.PI * this.clock / PERIOD_S));
      requestAnimationFrame(tick);
    };
    requestAnimationFrame(tick);
  }

  // The view every viewer opens with: from above the side, tilted so the line fills the width.
  Viewer.prototype.fit = function () {
    const T = window.FS3;
    const dir = new T.Vector3(0.3, -1.0, 0.4).normalize();
    const span = Math.max(this.size.x, this.size.y, this.size.z);
    this.camera.position.copy(this.centre).addScaledVector(dir, 4 * span);
    this.controls.target.copy(this.centre);
    this.camera.lookAt(this.centre);
    this.camera.updateMatrixWorld();
    // the box's corners in the view's axes: the frustum holds them with a margin
    const inv = this.camera.matrixWorldInverse;
    let w = 0, h = 0;
    for (const cx of [0, 1]) for (const cy of [0, 1]) for (const cz of [0, 1]) {
      const p = new T.Vector3(
        this.centre.x + (cx - 0.5) * this.size.x,
        this.centre.y + (cy - 0.5) * this.size.y,
        this.centre.z + (cz - 0.5) * this.size.z).applyMatrix4(inv);
      w = Math.max(w, Math.abs(p.x));
      h = Math.max(h, Math.abs(p.y));
    }
    const aspect = this.width / this.height / 1.1; // the frustum is 2.2·half wide
    // a margin for the colour bar (right), the triad (left) and the labels (above and below)
    const half = Math.max(w * 1.06, h * 1.5 * aspect);
    this.camera.left = -half;
    this.camera.right = half * 1.2; // the drawing centred left of the colour bar
    this.camera.top = half / aspect;
    this.camera.bottom = -half / aspect;
    this.camera.zoom = 1;
    this.camera.updateProjectionMatrix();
    this.controls.update();
    this.placeLabels();
    this.drawTriad();
    this.drawScale();
  };

  Viewer.prototype.update = function () {
    const m = this.modes[this.mode].meta;
    const deg = Math.round(this.amplitude * 180 / Math.PI);
    this.ampText.textContent = `${deg}°`;
    const what = { twist: 'twist', stress: 'shear stress', energy: 'strain-energy density' }[this.colour];
    this.caption.textContent =
      `${this.data.model} - mode ${m.index}: ${fmt(m.frequency_hz)} Hz, damping ${fmt(100 * m.damping_ratio)} %. ` +
      `Twist drawn ${deg}° at the largest station rotation (exaggerated); colour: ${what} at ` +
      `${fmt(1e3 * this.data.amplitude)} mrad peak station rotation, following the motion; grey lines: ` +
      `undeformed; black hands: each station's twist, grey: at rest. One period of the mode in ${PERIOD_S} s. ` +
      'Drag to turn, scroll to zoom, right-drag to pan.';
    this.drawColourbar();
  };

  Viewer.prototype.range = function () {
    const mode = this.modes[this.mode];
    if (this.colour === 'twist') return { lo: -mode.meta.twist_max, hi: mode.meta.twist_max, unit: 'mrad' };
    if (this.colour === 'stress') return { lo: -mode.meta.stress.max, hi: mode.meta.stress.max, unit: 'MPa' };
    return { lo: 0, hi: mode.meta.energy.max, unit: 'J/m³' };
  };

  Viewer.prototype.frame = function (s) {
    const mode = this.modes[this.mode];
    const base = this.base, pos = this.positions, col = this.colours;
    const phi = mode.phi, lat = mode.lateral, A = this.amplitude * s;
    const n = this.data.n_points;
    for (let i = 0; i < n; i++) {
      const a = A * phi[i], c = Math.cos(a), sn = Math.sin(a);
      const y = base[3 * i + 1], z = base[3 * i + 2];
      pos[3 * i + 1] = y * c - z * sn + (lat ? lat[2 * i] * A : 0);
      pos[3 * i + 2] = y * sn + z * c + (lat ? lat[2 * i + 1] * A : 0);
    }
    const r = this.range();
    if (this.colour === 'energy') {
      const e = mode.energy, top = r.hi || 1, s2 = s * s;
      for (let i = 0; i < n; i++) mapColour(SEQUENTIAL, (e[i] * s2) / top, col, 3 * i);
    } else {
      const v = this.colour === 'twist' ? phi : mode.stress;
      const f = this.colour === 'twist' ? 1e3 * this.data.amplitude : 1;
      const top = r.hi || 1;
      for (let i = 0; i < n; i++) mapColour(DIVERGING, 0.5 + 0.5 * (v[i] * f * s) / top, col, 3 * i);
    }
    this.geometry.attributes.position.needsUpdate = true;
    this.geometry.attributes.color.needsUpdate = true;
    this.geometry.computeVertexNormals();
    for (const d of this.discs) d.group.rotation.x = A * d.data.phi[this.mode];
    for (const h of this.hands) h.group.rotation.x = A * h.data.phi[this.mode];
    this.renderer.render(this.scene, this.camera);
  };

  Viewer.prototype.drawColourbar = function () {
    const cv = this.colourbar, g = cv.getContext('2d');
    const r = this.range();
    const W = cv.width, H = cv.height, x0 = 8, bw = 16, top = 30, bottom = H - 10;
    g.clearRect(0, 0, W, H);
    g.fillStyle = 'rgba(255,255,255,0.85)';
    g.fillRect(0, 0, W, H);
    const stops = this.colour === 'energy' ? SEQUENTIAL : DIVERGING;
    const rgb = new Float32Array(3);
    for (let y = top; y <= bottom; y++) {
      mapColour(stops, (bottom - y) / (bottom - top), rgb, 0);
      g.fillStyle = `rgb(${255 * rgb[0]},${255 * rgb[1]},${255 * rgb[2]})`;
      g.fillRect(x0, y, bw, 1);
    }
    g.strokeStyle = '#333';
    g.strokeRect(x0, top, bw, bottom - top);
    g.fillStyle = '#111';
    g.font = '12px sans-serif';
    g.textBaseline = 'alphabetic';
    g.fillText(r.unit, x0, 14); // the title, clear of the ticks below it
    g.textBaseline = 'middle';
    const hi = r.hi || 1, lo = r.lo;
    for (const t of niceTicks(lo, hi, 5)) {
      const y = bottom - (t - lo) / (hi - lo) * (bottom - top);
      g.fillRect(x0 + bw, y, 4, 1);
      g.fillText(fmt(t), x0 + bw + 7, y);
    }
  };

  Viewer.prototype.drawTriad = function () {
    const T = window.FS3;
    const g = this.triad.getContext('2d');
    const c = 45, L = 30;
    g.clearRect(0, 0, 90, 90);
    const q = this.camera.quaternion.clone().invert();
    const axes = [['x', 0xc0392b, [1, 0, 0]], ['y', 0x27ae60, [0, 1, 0]], ['z', 0x2c3e80, [0, 0, 1]]];
    g.font = 'bold 12px sans-serif';
    g.textAlign = 'center';
    g.textBaseline = 'middle';
    for (const [name, colour, v] of axes) {
      const p = new T.Vector3(...v).applyQuaternion(q);
      const hex = '#' + colour.toString(16).padStart(6, '0');
      g.strokeStyle = hex;
      g.fillStyle = hex;
      g.lineWidth = 2;
      g.beginPath();
      g.moveTo(c, c);
      g.lineTo(c + L * p.x, c - L * p.y);
      g.stroke();
      g.fillText(name, c + (L + 9) * p.x, c - (L + 9) * p.y);
    }
  };

  Viewer.prototype.drawScale = function () {
    this.scalebar.innerHTML = '';
    if (this.data.lengths === false) { // a chain given by numbers: no lengths to show
      el('div', { text: 'schematic: no lengths given' }, this.scalebar);
      return;
    }
    // orthographic: metres per pixel are the same everywhere in the picture
    const perPixel = (this.camera.right - this.camera.left) / this.camera.zoom / this.width;
    const len = niceLength(perPixel * this.width * 0.2);
    const px = Math.round(len / perPixel);
    el('div', { class: 'fs-scale-bar', style: `width:${px}px` }, this.scalebar);
    el('div', { text: len >= 1 ? `${fmt(len)} m` : `${fmt(len * 1000)} mm` }, this.scalebar);
  };

  Viewer.prototype.makeLabels = function () {
    this.labels = this.data.labels.map((l) => ({ data: l, div: el('div', { class: 'fs-label', text: l.text }, this.overlay) }));
  };

  // Labels beside their anchors, moved up or down (alternating) until none overlaps another,
  // each joined to its anchor by a leader line.
  Viewer.prototype.placeLabels = function () {
    if (!this.labels) return;
    const T = window.FS3;
    this.camera.updateMatrixWorld();
    const placed = [];
    while (this.svg.firstChild) this.svg.removeChild(this.svg.firstChild);
    const items = this.labels.map((l) => {
      const p = new T.Vector3(...l.data.p).project(this.camera);
      return { l, x: (p.x + 1) / 2 * this.width, y: (1 - p.y) / 2 * this.height, below: l.data.below };
    }).sort((a, b) => a.x - b.x);
    for (const it of items) {
      const w = it.l.div.offsetWidth || 60, h = it.l.div.offsetHeight || 16;
      // candidate rows: the anchor's own side first (above, or below for a station under the shaft),
      // then alternating sides, each row a label's height further out
      let best = null;
      for (let k = 0; k < 24 && best === null; k++) {
        const side = (k % 2 === 0) === !it.below ? -1 : 1;
        const out = 12 + Math.floor(k / 2) * (h + 4);
        const box = { x: it.x - w / 2, y: side < 0 ? it.y - out - h : it.y + out, w, h };
        const clash = placed.some((b) => box.x < b.x + b.w + 4 && b.x < box.x + box.w + 4 && box.y < b.y + b.h + 2 && b.y < box.y + box.h + 2);
        if (!clash) best = box;
      }
      best = best || { x: it.x - w / 2, y: it.y - h - 10, w, h };
      best.x = Math.min(Math.max(best.x, 2), this.width - w - 2);
      best.y = Math.min(Math.max(best.y, 2), this.height - h - 2);
      placed.push(best);
      it.l.div.style.left = best.x + 'px';
      it.l.div.style.top = best.y + 'px';
      const line = document.createElementNS('http://www.w3.org/2000/svg', 'line');
      line.setAttribute('x1', it.x);
      line.setAttribute('y1', it.y);
      line.setAttribute('x2', best.x + w / 2);
      line.setAttribute('y2', best.y < it.y ? best.y + h : best.y);
      line.setAttribute('stroke', '#555');
      line.setAttribute('stroke-width', '1');
      this.svg.appendChild(line);
    }
  };

  window.flexshaftViewers = window.flexshaftViewers || [];
  // Start the viewer in the element with id `rootId` from the JSON in the script with id `dataId`.
  window.flexshaftViewer = function (rootId, dataId) {
    const data = JSON.parse(document.getElementById(dataId).textContent);
    const v = new Viewer(document.getElementById(rootId), data);
    window.flexshaftViewers.push(v);
    return v;
  };
})();
