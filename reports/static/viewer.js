/* cassi-farm task viewer: the animated face of one task file, every version, in 3D, with the
   recording's pellets (markers in 3D, traces on the timeline), labels, sound and the rubric's
   events on one timeline; A/B side by side, overlaid or as B's distance to A.
   Data: window.CASSI_VIEWER (written by cassi.reports.viewer). Strings from data files are
   only ever set as text (textContent, option.text), never as HTML. */
(function () {
  "use strict";
  const D = window.CASSI_VIEWER;
  const $ = (id) => document.getElementById(id);
  const status = $("status");
  const DTYPES = { float32: Float32Array, int16: Int16Array, int32: Int32Array, uint16: Uint16Array,
                   int8: Int8Array, uint8: Uint8Array };
  // pellet markers: the recording's (measured) and the version's pellet sites (model), as in
  // the page's legend; radius in mm (an XRMB pellet is 2-3 mm across)
  const PELLET_COLOURS = { measured: 0x111111, model: 0x00c8c8 }, PELLET_RADIUS_MM = { measured: 2.2, model: 1.4 };
  // the difference view's colour map (viridis, sRGB stops; the scale bar is the same gradient)
  const RAMP = ["#440154", "#472d7b", "#3b528b", "#2c728e", "#21918c", "#28ae80", "#5ec962", "#addc30", "#fde725"];

  function fail(err) {
    status.textContent = "error: " + (err && err.message ? err.message : err);
    status.className = "error";
    console.error(err);
  }

  async function decode(a) {
    let bytes = Uint8Array.from(atob(a.b64), (c) => c.charCodeAt(0));
    if (a.deflate) {
      const stream = new Blob([bytes]).stream().pipeThrough(new DecompressionStream("deflate"));
      bytes = new Uint8Array(await new Response(stream).arrayBuffer());
    }
    const T = DTYPES[a.dtype];
    return new T(bytes.buffer, bytes.byteOffset, bytes.byteLength / T.BYTES_PER_ELEMENT);
  }

  // ---- versions: geometry per kept frame -------------------------------------------------
  async function loadVersion(name) {
    const v = D.version_data[name];
    const out = { name: name, events: v.events, renders: v.renders, parts: v.parts,
                  palateTop: v.palate_top,
                  // absent in data written before the map was kept: no markers, no mm
                  unitsPerMm: v.units_per_mm || null, origin: v.xrmb_origin || null };
    for (const key of ["frames", "time_ms", "base", "moving", "q0", "dq", "gather", "sign",
                       "triangles", "part_of", "model"]) out[key] = await decode(v[key]);
    const K = out.frames.length, M = out.moving.length, step = v.step;
    // every kept frame's moving vertices (face rows), from the first frame and the changes
    const pos = new Float32Array(K * M * 3);
    const acc = new Int32Array(M * 3);
    for (let i = 0; i < M * 3; i++) acc[i] = out.q0[i];
    for (let k = 0; k < K; k++) {
      if (k > 0) { const off = (k - 1) * M * 3; for (let i = 0; i < M * 3; i++) acc[i] += out.dq[off + i]; }
      for (let i = 0; i < M * 3; i++) pos[k * M * 3 + i] = acc[i] * step;
    }
    out.pos = pos; out.K = K; out.M = M;
    out.face = Float32Array.from(out.base);   // face rows of the frame shown
    return out;
  }

  function keptIndex(frames, row) {   // last kept frame <= row
    let lo = 0, hi = frames.length - 1;
    if (row <= frames[0]) return 0;
    if (row >= frames[hi]) return hi;
    while (hi - lo > 1) { const mid = (lo + hi) >> 1; if (frames[mid] <= row) lo = mid; else hi = mid; }
    return lo;
  }

  function setFace(ver, row) {
    const f = ver.frames, k = keptIndex(f, row);
    const k2 = Math.min(k + 1, ver.K - 1);
    const t = k2 > k && row > f[k] ? Math.min(1, (row - f[k]) / (f[k2] - f[k])) : 0;
    const M = ver.M, a = k * M * 3, b = k2 * M * 3;
    for (let m = 0; m < M; m++) {
      const r = ver.moving[m] * 3;
      for (let c = 0; c < 3; c++) {
        const i = m * 3 + c;
        ver.face[r + c] = ver.pos[a + i] + t * (ver.pos[b + i] - ver.pos[a + i]);
      }
    }
    return k;
  }

  // Parke (x forward, y left, z up) -> three.js (glTF axes): (y, z, x)
  function writeMerged(ver, attr) {
    const g = ver.gather, s = ver.sign, F = ver.face, arr = attr.array;
    for (let w = 0; w < g.length; w++) {
      const r = g[w] * 3;
      arr[w * 3] = F[r + 1] * s[w]; arr[w * 3 + 1] = F[r + 2]; arr[w * 3 + 2] = F[r];
    }
    attr.needsUpdate = true;
  }

  function buildMesh(ver, style) {   // style: "solid", "wire" or "diff" (coloured per vertex)
    const geo = new THREE.BufferGeometry();
    const attr = new THREE.BufferAttribute(new Float32Array(ver.gather.length * 3), 3);
    geo.setAttribute("position", attr);
    if (style === "diff") geo.setAttribute("color", new THREE.BufferAttribute(new Float32Array(ver.gather.length * 3), 3));
    // triangles sorted by part, one draw group (material) per part
    const T = ver.part_of.length, order = [];
    for (let i = 0; i < T; i++) order.push(i);
    order.sort((x, y) => ver.part_of[x] - ver.part_of[y] || x - y);
    const idx = new Uint32Array(T * 3);
    order.forEach((t, j) => { for (let c = 0; c < 3; c++) idx[j * 3 + c] = ver.triangles[t * 3 + c]; });
    geo.setIndex(new THREE.BufferAttribute(idx, 1));
    const mats = [];
    let start = 0;
    while (start < T) {
      const p = ver.part_of[order[start]];
      let end = start;
      while (end < T && ver.part_of[order[end]] === p) end++;
      geo.addGroup(start * 3, (end - start) * 3, mats.length);
      const spec = ver.parts[p];
      const col = new THREE.Color().setRGB(spec.rgb[0], spec.rgb[1], spec.rgb[2]);
      mats.push(style === "wire" ? new THREE.MeshBasicMaterial({ color: col, wireframe: true, transparent: true, opacity: 0.55 })
              : style === "diff" ? new THREE.MeshStandardMaterial({ vertexColors: true, roughness: 0.9, metalness: 0,
                                                                    side: THREE.DoubleSide })
              : new THREE.MeshStandardMaterial({ color: col, roughness: spec.roughness, metalness: 0,
                                                 side: THREE.DoubleSide }));
      start = end;
    }
    const mesh = new THREE.Mesh(geo, mats);
    mesh.frustumCulled = false;   // the positions move every frame; the bounds would go stale
    mesh.userData.attr = attr;
    return mesh;
  }

  // ---- A/B difference: each of B's vertices' distance to the same vertex of A, mm ----------
  function sameArray(x, y) {
    if (x.length !== y.length) return false;
    for (let i = 0; i < x.length; i++) if (x[i] !== y[i]) return false;
    return true;
  }

  function diffWhyNot(a, b) {   // why no difference map can be drawn, or null
    if (!b) return "Difference view: choose a version B; B is coloured by its distance to A.";
    const na = a.base.length / 3, nb = b.base.length / 3;
    if (na !== nb)
      return "No difference map: A (" + a.name + ") has " + na + " vertices, B (" + b.name + ") " + nb
        + "; the distance is taken vertex by vertex, so both must animate the same face.";
    if (!sameArray(a.triangles, b.triangles) || !sameArray(a.gather, b.gather) || !sameArray(a.sign, b.sign))
      return "No difference map: A and B have " + na + " vertices each but not the same faces (triangles).";
    if (!b.unitsPerMm)
      return "No difference map: this report's data has no scale (Parke units per mm); report a newer run.";
    return null;
  }

  // both faces set to one row: per face row, |A - B| in mm (Parke units over B's units per mm)
  function distances(a, b, out) {
    const A = a.face, B = b.face, s = b.unitsPerMm;
    let most = 0;
    for (let r = 0; r < out.length; r++) {
      const dx = A[r * 3] - B[r * 3], dy = A[r * 3 + 1] - B[r * 3 + 1], dz = A[r * 3 + 2] - B[r * 3 + 2];
      out[r] = Math.sqrt(dx * dx + dy * dy + dz * dz) / s;
      if (out[r] > most) most = out[r];
    }
    return most;
  }

  function taskMaxDistance(a, b) {   // the scale bar's top: the largest distance at any kept frame
    const d = new Float32Array(a.base.length / 3);
    let most = 0;
    for (const f of [a.frames, b.frames]) for (let k = 0; k < f.length; k++) {
      setFace(a, f[k]); setFace(b, f[k]); most = Math.max(most, distances(a, b, d));
    }
    return most;
  }

  const RAMP_RGB = RAMP.map((h) => [1, 3, 5].map((i) => parseInt(h.slice(i, i + 2), 16) / 255));
  function rampColour(t, col) {   // t in 0..1 -> three.js (linear) colour, interpolated in sRGB like the CSS bar
    const x = Math.max(0, Math.min(1, t)) * (RAMP.length - 1), i = Math.min(RAMP.length - 2, Math.floor(x)), f = x - i;
    const a = RAMP_RGB[i], b = RAMP_RGB[i + 1];
    return col.setRGB(a[0] + f * (b[0] - a[0]), a[1] + f * (b[1] - a[1]), a[2] + f * (b[2] - a[2]), THREE.SRGBColorSpace);
  }

  function colourByDistance(mesh, ver, mm, top) {
    const attr = mesh.geometry.getAttribute("color"), g = ver.gather, col = new THREE.Color();
    for (let w = 0; w < g.length; w++) {
      rampColour(mm[g[w]] / top, col);
      attr.array[w * 3] = col.r; attr.array[w * 3 + 1] = col.g; attr.array[w * 3 + 2] = col.b;
    }
    attr.needsUpdate = true;
  }

  function diffBar() {   // the scale bar (or why there is none) over the 3D view
    const el = $("diffbar");
    el.hidden = S.mode !== "diff";
    if (el.hidden) return;
    el.replaceChildren();
    const line = (text) => { const d = document.createElement("div"); d.textContent = text; el.appendChild(d); return d; };
    el.title = "";
    if (S.diffWhy) { line(S.diffWhy).className = "why"; return; }
    const top = S.diff.top;
    el.title = "each vertex of B coloured by its distance to the same vertex of A (Parke units over B's units per mm);"
      + " the scale runs from 0 to the largest distance at any kept frame";
    line("B's distance to A, mm").style.fontWeight = "bold";
    const ramp = document.createElement("div"); ramp.className = "ramp";
    ramp.style.background = "linear-gradient(to right, " + RAMP.join(", ") + ")"; el.appendChild(ramp);
    const ticks = document.createElement("div"); ticks.className = "ticks";
    for (const v of [0, top / 2, top]) { const t = document.createElement("span"); t.textContent = v === 0 ? "0" : v.toFixed(2); ticks.appendChild(t); }
    ticks.lastChild.textContent += " mm";
    el.appendChild(ticks);
    line("this frame: up to " + S.diff.frameMax.toFixed(2) + " mm").className = "meta";
  }

  // ---- pellet markers: the recording's pellets and the model's sites, as spheres ------------
  function sphere(radius) {   // a latitude-longitude sphere (the vendored subset has no SphereGeometry)
    const W = 14, H = 9, pos = [], idx = [];
    for (let j = 0; j <= H; j++) {
      const v = (j / H) * Math.PI;
      for (let i = 0; i <= W; i++) {
        const u = (i / W) * 2 * Math.PI;
        pos.push(-radius * Math.cos(u) * Math.sin(v), radius * Math.cos(v), radius * Math.sin(u) * Math.sin(v));
      }
    }
    for (let j = 0; j < H; j++) for (let i = 0; i < W; i++) {
      const a = j * (W + 1) + i, b = a + W + 1;
      if (j > 0) idx.push(a, b, a + 1);
      if (j < H - 1) idx.push(b, b + 1, a + 1);
    }
    const geo = new THREE.BufferGeometry();
    geo.setAttribute("position", new THREE.Float32BufferAttribute(pos, 3));
    geo.setIndex(idx); geo.computeVertexNormals();
    return geo;
  }

  // A scene of its own, drawn over the face after its depth is cleared, so that the tongue's
  // pellets show through the cheek (VisArtico draws its sensors so).
  function pelletMarkers(ver) {
    if (!ver.unitsPerMm || !ver.origin) return null;
    const scene = new THREE.Scene(); lights(scene);
    const out = { scene: scene, ver: ver, measured: [], model: [] };
    for (const kind of ["measured", "model"]) {
      // the model's smaller ball is drawn last, over the measured one, so a pair that meets shows both
      const geo = sphere(PELLET_RADIUS_MM[kind] * ver.unitsPerMm);
      const mat = new THREE.MeshStandardMaterial({ color: PELLET_COLOURS[kind], roughness: 0.35, metalness: 0,
                                                   depthTest: kind === "measured" });
      for (let p = 0; p < D.pellets.length; p++) {
        const m = new THREE.Mesh(geo, mat); m.renderOrder = kind === "model" ? 2 : 1; scene.add(m); out[kind].push(m);
      }
    }
    const lineGeo = new THREE.BufferGeometry();
    lineGeo.setAttribute("position", new THREE.BufferAttribute(new Float32Array(D.pellets.length * 6), 3));
    out.lines = new THREE.LineSegments(lineGeo, new THREE.LineBasicMaterial({ color: 0x555555 }));
    out.lines.frustumCulled = false; scene.add(out.lines);
    return out;
  }

  function xyAt(arr, frames, row, p) {   // a pellet's XRMB (x, y) mm at a row, between kept frames; null if not valid
    const n = D.pellets.length, k = keptIndex(frames, row), k2 = Math.min(k + 1, frames.length - 1);
    const t = k2 > k && row > frames[k] ? Math.min(1, (row - frames[k]) / (frames[k2] - frames[k])) : 0;
    const out = [];
    for (const c of [0, 1]) {
      const a = arr[(k * n + p) * 2 + c], b = arr[(k2 * n + p) * 2 + c];
      out.push(a + t * (b - a));
    }
    return isFinite(out[0]) && isFinite(out[1]) ? out : null;
  }

  function placePellets(m, row) {
    if (!m) return;
    const ver = m.ver, s = ver.unitsPerMm, o = ver.origin, line = m.lines.geometry.getAttribute("position");
    // XRMB (x forward, y up) mm -> the version's face as it maps the pellets (XrmbToParke, thesis
    // 4.1.1): Parke (x, z) = (x, y) * units_per_mm + xrmb_origin, on the midsagittal plane
    // (Parke y = 0) -> three.js (Parke y, z, x)
    const place = (mesh, xy) => {
      mesh.visible = xy !== null;
      if (xy) mesh.position.set(0, xy[1] * s + o[1], xy[0] * s + o[0]);
    };
    for (let p = 0; p < D.pellets.length; p++) {
      const meas = xyAt(S.measured, S.measuredFrames, row, p), mod = xyAt(ver.model, ver.frames, row, p);
      place(m.measured[p], meas); place(m.model[p], mod);
      const a = m.measured[p].position, b = m.model[p].position, both = meas && mod;
      line.array.set(both ? [a.x, a.y, a.z, b.x, b.y, b.z] : [0, 0, 0, 0, 0, 0], p * 6);
    }
    line.needsUpdate = true;
  }

  // ---- state ---------------------------------------------------------------------------
  const S = { row: 0, playing: false, speed: 0.25, view: "front", a: null, b: null, mode: "side",
              check: null, pellet: 2, loaded: {}, first: 0, last: 0, pellets: true,
              diffWhy: null, diff: null };

  let renderer, sceneA, sceneB, camera, controls, meshA, meshB, meshBwire, clipPlanes = [];
  let pelletsA = null, pelletsB = null;
  const box = $("three");

  function lights(scene) {
    scene.add(new THREE.HemisphereLight(0xffffff, 0x444444, 1.6));
    const key = new THREE.DirectionalLight(0xffffff, 2.2); key.position.set(-400, 500, 900); scene.add(key);
    const fill = new THREE.DirectionalLight(0xffffff, 0.8); fill.position.set(700, 100, 500); scene.add(fill);
    const back = new THREE.DirectionalLight(0xffffff, 0.6); back.position.set(0, 300, -800); scene.add(back);
  }

  function initThree() {
    renderer = new THREE.WebGLRenderer({ antialias: true, preserveDrawingBuffer: true });
    renderer.setPixelRatio(1);
    renderer.setSize(box.clientWidth, box.clientHeight);
    renderer.setScissorTest(true);
    renderer.localClippingEnabled = true;
    box.appendChild(renderer.domElement);
    sceneA = new THREE.Scene(); sceneB = new THREE.Scene();
    sceneA.background = new THREE.Color(0xf4f4f4); sceneB.background = new THREE.Color(0xf4f4f4);
    lights(sceneA); lights(sceneB);
    camera = new THREE.PerspectiveCamera(22, 1, 10, 100000);
    controls = new THREE.OrbitControls(camera, renderer.domElement);
    controls.addEventListener("change", draw);
    // A lost WebGL context (driver reset, too many contexts) is restored by three.js's renderer;
    // the page draws on demand, so it draws again once the context is back.
    const cv = renderer.domElement;
    cv.addEventListener("webglcontextlost", (ev) => { ev.preventDefault(); status.textContent = "WebGL context lost: restoring…"; });
    cv.addEventListener("webglcontextrestored", () => { status.textContent = "ready"; requestAnimationFrame(draw); });
    window.addEventListener("resize", resize);
    if (window.ResizeObserver) new ResizeObserver(resize).observe(box);   // the layout's share, not only the window
  }

  function resize() {   // the 3D view and the timeline follow the window's size
    if (renderer) renderer.setSize(box.clientWidth, box.clientHeight);
    TL.width = Math.max(320, Math.round(TL.clientWidth));
    draw(); drawTimeline();
  }

  function label(id, text, left) {
    let el = $(id);
    if (!el) { el = document.createElement("div"); el.id = id; el.className = "vlabel"; box.appendChild(el); }
    el.textContent = text; el.style.left = left + "px"; el.style.display = text ? "" : "none";
  }

  function setView(name) {
    const v = D.views[name];
    S.view = name;
    camera.position.set(...v.origin); camera.up.set(...v.up); camera.fov = v.fov;
    controls.target.set(...v.target); camera.updateProjectionMatrix(); controls.update();
    clipPlanes.length = 0;
    // keep y >= 0 (the left half; faces on the midsagittal plane, the tongue's among them, stay)
    if (v.half) clipPlanes.push(new THREE.Plane(new THREE.Vector3(1, 0, 0), 0.5));
    if (v.clip_above_palate !== null && S.a && S.a.palateTop !== null)
      clipPlanes.push(new THREE.Plane(new THREE.Vector3(0, -1, 0), S.a.palateTop + v.clip_above_palate));
    for (const m of [meshA, meshB, meshBwire]) if (m) for (const mat of m.material) {
      mat.clippingPlanes = clipPlanes.slice(); mat.needsUpdate = true;
    }
    document.querySelectorAll("button[data-view]").forEach((b) => b.classList.toggle("on", b.dataset.view === name));
    showRenders(); writeHash();
    draw();
  }

  async function setVersions() {
    const an = $("va").value, bn = $("vb").value;
    if (!S.loaded[an]) S.loaded[an] = await loadVersion(an);
    if (bn && !S.loaded[bn]) S.loaded[bn] = await loadVersion(bn);
    S.a = S.loaded[an]; S.b = bn ? S.loaded[bn] : null; S.mode = $("mode").value;
    writeHash();
    for (const m of [meshA, meshB, meshBwire]) if (m) m.parent.remove(m);
    meshA = buildMesh(S.a, "solid"); sceneA.add(meshA);
    meshB = meshBwire = null;
    S.diffWhy = S.mode === "diff" ? diffWhyNot(S.a, S.b) : null;
    S.diff = null;
    if (S.b) {
      if (S.mode === "overlay") { meshBwire = buildMesh(S.b, "wire"); sceneA.add(meshBwire); }
      else if (S.mode === "diff" && !S.diffWhy) {
        meshB = buildMesh(S.b, "diff"); sceneB.add(meshB);
        const top = taskMaxDistance(S.a, S.b);
        S.diff = { top: top > 0 ? top : 1, mm: new Float32Array(S.a.base.length / 3), frameMax: 0 };
      } else { meshB = buildMesh(S.b, "solid"); sceneB.add(meshB); }
    }
    pelletsA = pelletMarkers(S.a);
    pelletsB = S.b && S.mode !== "overlay" ? pelletMarkers(S.b) : null;
    $("pellets").disabled = !pelletsA;
    $("pellets").title = pelletsA ? "the recording's pellets and the model's pellet sites in 3D (key P)"
      : "no pellet markers: this report's data has no map from the XRMB frame to the face";
    setView(S.view);
    drawEvents();
    go(S.row);
  }

  function port(scene, pellets, x, w, H) {   // one viewport: the face, then the pellets over it
    renderer.setViewport(x, 0, w, H); renderer.setScissor(x, 0, w, H); renderer.render(scene, camera);
    if (pellets && S.pellets) {
      renderer.autoClear = false; renderer.clearDepth(); renderer.render(pellets.scene, camera); renderer.autoClear = true;
    }
  }

  function draw() {
    if (!renderer) return;
    const W = box.clientWidth, H = box.clientHeight;
    const split = S.b && S.mode !== "overlay";
    const w = split ? Math.floor(W / 2) : W;
    camera.aspect = w / H; camera.updateProjectionMatrix();
    port(sceneA, pelletsA, 0, w, H);
    if (split) port(sceneB, pelletsB, w, W - w, H);
    label("labelA", S.a ? "A: " + S.a.name + (S.b && S.mode === "overlay" ? "  (B: " + S.b.name + ", wireframe)" : "") : "", 4);
    label("labelB", split ? "B: " + S.b.name + (S.diff ? ", coloured by its distance to A" : "") : "", w + 4);
  }

  // ---- time ----------------------------------------------------------------------------
  function rowTime(row) {   // seconds on the recording's clock (the sound's and the labels')
    const v = S.a; const k = keptIndex(v.frames, row);
    return v.time_ms[k] / 1000 + (row - v.frames[k]) / D.rate_hz;
  }
  const timeRow = (sec) => { const v = S.a; return v.frames[0] + (sec - v.time_ms[0] / 1000) * D.rate_hz; };

  function go(row) {
    row = Math.max(S.first, Math.min(S.last, Math.round(row)));
    S.row = row;
    if (meshA) { setFace(S.a, row); writeMerged(S.a, meshA.userData.attr); meshA.geometry.computeVertexNormals(); }
    const mb = meshB || meshBwire;
    if (mb) { setFace(S.b, row); writeMerged(S.b, mb.userData.attr); mb.geometry.computeVertexNormals(); }
    if (S.diff) { S.diff.frameMax = distances(S.a, S.b, S.diff.mm); colourByDistance(meshB, S.b, S.diff.mm, S.diff.top); }
    diffBar();
    placePellets(pelletsA, row); placePellets(pelletsB, row);
    $("frame").textContent = String(row);
    $("time").textContent = "t = " + rowTime(row).toFixed(3) + " s";
    $("scrub").value = String(row);
    showRenders(); if (!S.playing) writeHash();
    draw(); drawTimeline();
  }

  // ---- the address: #frame=&a=&b=&check=&view= follows the state, and the state the address
  let hashWritten = location.hash;
  function writeHash() {
    if (!S.a) return;
    const p = new URLSearchParams();
    p.set("frame", String(S.row)); p.set("a", S.a.name);
    if (S.b) p.set("b", S.b.name);
    if (S.check) p.set("check", S.check);
    p.set("view", S.view);
    if (S.mode !== "side") p.set("mode", S.mode);
    if (!S.pellets) p.set("pellets", "0");
    const h = "#" + p.toString();
    if (h !== location.hash) history.replaceState(null, "", h);
    hashWritten = location.hash;
  }

  function readHash() {   // what the address asks for; names the page does not know are ignored
    const params = new URLSearchParams(location.hash.slice(1));
    const a = params.get("a"), b = params.get("b");
    if (a && D.versions.includes(a)) $("va").value = a;
    if (params.has("b")) $("vb").value = b && D.versions.includes(b) ? b : "";
    if (["overlay", "side", "diff"].includes(params.get("mode"))) $("mode").value = params.get("mode");
    S.pellets = params.get("pellets") !== "0"; $("pellets").checked = S.pellets;
    S.check = params.get("check");
    // open in the view the check is judged from (the link says which)
    const v = params.get("view");
    if (v && Object.prototype.hasOwnProperty.call(D.views, v)) S.view = v;
    if (params.has("frame") && isFinite(Number(params.get("frame")))) S.row = Number(params.get("frame"));
  }

  async function followHash() {
    if (location.hash === hashWritten) return;
    hashWritten = location.hash;
    pause(); readHash();
    await setVersions();   // versions, view, events and frame, as the address says
  }

  function showRenders() {
    const el = $("renders");
    el.replaceChildren();
    for (const ver of [S.a, S.b]) {
      if (!ver) continue;
      const here = ver.renders.filter((r) => r.frame === S.row && r.view === S.view);
      const cap = document.createElement("div"); cap.className = "meta";
      if (!here.length) {
        cap.textContent = ver.name + ": no Mitsuba render of frame " + S.row + " (" + S.view + " view)";
        el.appendChild(cap);
        const have = ver.renders.filter((r) => r.view === S.view);
        if (have.length) {
          const near = have.reduce((a, r) => (Math.abs(r.frame - S.row) < Math.abs(a.frame - S.row) ? r : a));
          const b = document.createElement("button"); b.textContent = "go to the nearest render: frame " + near.frame;
          b.addEventListener("click", () => { pause(); go(near.frame); }); el.appendChild(b);
        }
        continue;
      }
      for (const r of here) {
        cap.textContent = ver.name + ": Mitsuba render, " + r.view + " view, frame " + r.frame;
        el.appendChild(cap);
        const wrap = document.createElement("div"); wrap.className = "render";
        const img = document.createElement("img"); img.src = r.href; img.alt = cap.textContent; wrap.appendChild(img);
        el.appendChild(wrap);
        if (r.mask) {
          const m = document.createElement("img"); m.src = r.mask; m.className = "mask";
          m.alt = "what the image checks read in this frame"; wrap.appendChild(m);
          const t = document.createElement("label"); t.className = "meta";
          const box = document.createElement("input"); box.type = "checkbox"; box.checked = true;
          box.addEventListener("change", () => { m.style.display = box.checked ? "" : "none"; });
          t.appendChild(box);
          t.appendChild(document.createTextNode(" the image checks' masks: lips red, upper teeth yellow, lower teeth cyan, tongue magenta, mouth opening blue"));
          el.appendChild(t);
        }
      }
    }
  }

  let last = null;
  function tick(now) {
    if (!S.playing) return;
    const audio = $("audio");
    if (D.audio && !audio.paused && S.speed === 1) {
      go(timeRow(audio.currentTime));
    } else {
      if (last !== null) go(S.row + (now - last) / 1000 * D.rate_hz * S.speed);
    }
    last = now;
    if (S.row >= S.last) { pause(); return; }
    requestAnimationFrame(tick);
  }
  function play() {
    if (S.row >= S.last) go(S.first);
    S.playing = true; last = null; $("play").textContent = "pause";
    const audio = $("audio");
    if (D.audio && S.speed === 1) { audio.currentTime = rowTime(S.row); audio.play().catch(() => {}); }
    requestAnimationFrame(tick);
  }
  function pause() {
    const was = S.playing;
    S.playing = false; $("play").textContent = "play"; $("audio").pause();
    if (was) writeHash();
  }

  function stepKept(dir) {
    pause();
    const f = S.a.frames; const k = keptIndex(f, S.row);
    if (dir > 0) go(f[Math.min(f.length - 1, f[k] > S.row ? k : k + 1)]);
    else go(f[Math.max(0, f[k] < S.row ? k : k - 1)]);
  }

  // ---- timeline ------------------------------------------------------------------------
  const TL = $("timeline"), ctx = TL.getContext("2d");
  // lanes (canvas pixels, top to bottom): A's events and B's in rows of their own, the time axis under all
  const PAD = 56, LANES = { labels: [4, 32], wave: [36, 64], trace: [68, 188], eventsA: [192, 218],
                            eventsB: [222, 248], axis: [250, 270] };
  const xOf = (row) => PAD + (TL.width - PAD - 6) * (row - S.first) / Math.max(1, S.last - S.first);
  const rowOf = (x) => S.first + (x - PAD) / (TL.width - PAD - 6) * (S.last - S.first);

  function series(arr, frames, pellet, axis) {
    const out = []; const n = frames.length;
    for (let k = 0; k < n; k++) out.push([frames[k], arr[(k * D.pellets.length + pellet) * 2 + axis]]);
    return out;
  }

  function drawTimeline() {
    if (!S.a) return;
    ctx.clearRect(0, 0, TL.width, TL.height);
    ctx.font = "11px sans-serif"; ctx.fillStyle = "#555";
    // labels
    const [l0, l1] = LANES.labels;
    ctx.fillText("labels", 2, l0 + 12);
    if (D.labels) {
      const tiers = [["words", l0, (l1 - l0) / 2], ["phones", l0 + (l1 - l0) / 2, (l1 - l0) / 2]];
      for (const [name, y, h] of tiers) for (const [s0, s1, txt] of (D.labels[name] || [])) {
        const x0 = Math.max(PAD, xOf(timeRow(s0))), x1 = Math.min(TL.width - 6, xOf(timeRow(s1)));
        if (x1 <= x0) continue;
        ctx.strokeStyle = "#bbb"; ctx.strokeRect(x0, y, x1 - x0, h - 1);
        ctx.fillStyle = "#333"; if (x1 - x0 > 8) ctx.fillText(txt, x0 + 2, y + h - 4);
      }
    } else { ctx.fillText("no alignment in this corpus", PAD, l0 + 12); }
    // waveform
    const [w0, w1] = LANES.wave; ctx.fillStyle = "#555"; ctx.fillText("sound", 2, w0 + 12);
    if (D.waveform) {
      const n = D.waveform.min.length, mid = (w0 + w1) / 2, amp = (w1 - w0) / 2;
      ctx.strokeStyle = "#4a6fa5"; ctx.beginPath();
      for (let i = 0; i < n; i++) {
        const x = xOf(timeRow((i / n) * D.waveform.seconds));
        if (x < PAD || x > TL.width - 6) continue;
        ctx.moveTo(x, mid - D.waveform.max[i] * amp); ctx.lineTo(x, mid - D.waveform.min[i] * amp);
      }
      ctx.stroke();
    } else { ctx.fillText("no sound in this corpus", PAD, w0 + 12); }
    // pellet traces
    const [t0, t1] = LANES.trace;
    const p = S.pellet, traces = [];
    for (const axis of [0, 1]) {
      traces.push({ pts: series(S.measured, S.measuredFrames, p, axis), style: [], axis: axis });
      traces.push({ pts: series(S.a.model, S.a.frames, p, axis), style: [6, 3], axis: axis });
      if (S.b) traces.push({ pts: series(S.b.model, S.b.frames, p, axis), style: [2, 3], axis: axis });
    }
    const half = (t1 - t0) / 2;
    for (const axis of [0, 1]) {
      const y0 = t0 + axis * half, vals = [];
      for (const tr of traces) if (tr.axis === axis) for (const [, v] of tr.pts) if (isFinite(v)) vals.push(v);
      let lo = Math.min(...vals), hi = Math.max(...vals); if (!(hi > lo)) { lo -= 1; hi += 1; }
      const yOf = (v) => y0 + 4 + (half - 8) * (1 - (v - lo) / (hi - lo));
      ctx.fillStyle = "#555"; ctx.fillText(D.pellets[p] + (axis ? " y" : " x"), 2, y0 + 12);
      ctx.fillText(hi.toFixed(1), 2, y0 + 24); ctx.fillText(lo.toFixed(1) + " mm", 2, y0 + half - 4);
      for (const tr of traces) {
        if (tr.axis !== axis) continue;
        ctx.setLineDash(tr.style); ctx.strokeStyle = axis ? "#b42318" : "#1f5fa8"; ctx.beginPath();
        let pen = false;
        for (const [row, v] of tr.pts) {
          if (!isFinite(v)) { pen = false; continue; }
          if (pen) ctx.lineTo(xOf(row), yOf(v)); else ctx.moveTo(xOf(row), yOf(v));
          pen = true;
        }
        ctx.stroke();
      }
      ctx.setLineDash([]);
    }
    // events: A's row, then B's, each labelled with its version
    for (const [ver, lane, tag] of [[S.a, LANES.eventsA, "A"], [S.b, LANES.eventsB, "B"]]) {
      const [e0, e1] = lane;
      ctx.fillStyle = "#555"; ctx.font = "bold 11px sans-serif"; ctx.fillText(tag + " events", 2, e0 + 11);
      ctx.font = "11px sans-serif";
      ctx.strokeStyle = "#ddd"; ctx.beginPath(); ctx.moveTo(PAD, e1 + 0.5); ctx.lineTo(TL.width - 6, e1 + 0.5); ctx.stroke();
      if (!ver) { ctx.fillText("no version B chosen", PAD, e0 + 15); continue; }
      ctx.fillText(ver.name, 2, e0 + 23, PAD - 4);
      for (const e of ver.events) for (const f of e.frames) {
        const x = xOf(f), h = Math.max(5, Math.min(e1 - e0 - 1, 5 + 6 * e.negatives));
        ctx.fillStyle = D.table_colours[e.table] || "#888";
        const hl = tag === "A" && e.check === S.check;
        ctx.fillRect(x - (hl ? 3 : 1.5), e1 - h, hl ? 6 : 3, h);
        if (hl) { ctx.strokeStyle = "#000"; ctx.strokeRect(x - 4, e1 - h - 1, 8, h + 1); }
      }
    }
    // time axis: seconds on the recording's clock (the sound's and the labels')
    const [a0] = LANES.axis;
    ctx.strokeStyle = "#444"; ctx.fillStyle = "#333"; ctx.beginPath(); ctx.moveTo(PAD, a0 + 0.5); ctx.lineTo(TL.width - 6, a0 + 0.5);
    for (const t of timeTicks()) {
      ctx.moveTo(t.x + 0.5, a0); ctx.lineTo(t.x + 0.5, a0 + 5);
      if (t.x + 2 + ctx.measureText(t.label).width < TL.width - 2) ctx.fillText(t.label, t.x + 2, a0 + 15);
    }
    ctx.stroke(); ctx.fillText("time", 2, a0 + 15);
    // cursor
    ctx.strokeStyle = "#000"; ctx.beginPath(); ctx.moveTo(xOf(S.row), 0); ctx.lineTo(xOf(S.row), TL.height); ctx.stroke();
  }

  function timeTicks() {   // whole steps of 0.1 .. 60 s, at least 80 px apart
    const t0 = rowTime(S.first), t1 = rowTime(S.last), pxPerS = (TL.width - PAD - 6) / Math.max(1e-6, t1 - t0);
    const step = [0.1, 0.2, 0.5, 1, 2, 5, 10, 15, 30, 60].find((s) => s * pxPerS >= 80) || 60;
    const out = [];
    for (let i = Math.ceil(t0 / step - 1e-9); i * step <= t1 + 1e-9; i++) {
      const sec = i * step;
      out.push({ seconds: sec, x: xOf(timeRow(sec)), label: (step < 1 ? sec.toFixed(1) : String(Math.round(sec))) + " s" });
    }
    return out;
  }

  function allEvents() {
    const out = [];
    for (const ver of [S.a, S.b]) if (ver) for (const e of ver.events) out.push(Object.assign({ version: ver.name }, e));
    return out;
  }

  function eventItem(e) {
    const li = document.createElement("li");
    li.dataset.check = e.check; li.dataset.version = e.version;
    if (e.check === S.check && e.version === S.a.name) li.className = "hl";
    const sw = document.createElement("span"); sw.className = "swatch"; sw.style.background = D.table_colours[e.table] || "#888";
    li.appendChild(sw);
    const t = document.createElement("span");
    t.textContent = e.version + " · Table " + e.table + " · " + e.text + " (" + e.check + ", " + e.component + "): "
      + e.negatives + " negative" + (e.negatives === 1 ? "" : "s") + (e.note ? " (" + e.note + ")" : "")
      + (e.value !== null ? ", value " + e.value.toPrecision(4) + " " + e.unit : "") + "; frame" + (e.frames.length === 1 ? " " : "s ");
    li.appendChild(t);
    for (const f of e.frames) {
      const b = document.createElement("button"); b.textContent = String(f); b.className = "evframe";
      b.addEventListener("click", () => { S.check = e.check; pause(); drawEvents(); go(f); });
      li.appendChild(b);
    }
    return li;
  }

  function drawEvents() {
    const ul = $("events"); ul.replaceChildren();
    const evs = allEvents(), fired = evs.filter((e) => e.negatives > 0 || e.raw_negatives > 0),
      silent = evs.filter((e) => e.negatives <= 0 && !(e.raw_negatives > 0));
    if (!fired.length) { const li = document.createElement("li"); li.textContent = "No check earned negatives on this task file."; ul.appendChild(li); }
    for (const e of fired) ul.appendChild(eventItem(e));
    if (silent.length) {
      const li = document.createElement("li"), det = document.createElement("details"), sum = document.createElement("summary");
      sum.textContent = silent.length + " silent check" + (silent.length === 1 ? "" : "s") + " (no negatives; the frame each points at)";
      det.appendChild(sum);
      const inner = document.createElement("ul");
      for (const e of silent) inner.appendChild(eventItem(e));
      det.appendChild(inner);
      det.open = silent.some((e) => e.check === S.check);
      li.appendChild(det); ul.appendChild(li);
    }
    focusEvent();
  }

  function focusEvent() {   // the highlighted event, above the fold beside the frame controls
    const box = $("focus"); box.replaceChildren();
    const e = S.a && allEvents().find((x) => x.check === S.check && x.version === S.a.name);
    box.hidden = !e;
    if (e) box.appendChild(eventItem(e));
  }

  function setPellets(on) {
    S.pellets = on; $("pellets").checked = on; writeHash(); draw();
  }

  function toggleHelp(open) {
    const el = $("help"), show = open === undefined ? el.hidden : open;
    el.hidden = !show; $("helpbtn").setAttribute("aria-expanded", String(show));
    $("helpbtn").classList.toggle("on", show);
  }

  // ---- start ---------------------------------------------------------------------------
  async function start() {
    const va = $("va"), vb = $("vb");
    D.pellets.forEach((name, i) => { const o = document.createElement("option"); o.value = String(i); o.text = name; $("pellet").appendChild(o); });
    $("pellet").value = String(S.pellet);
    S.measured = await decode(D.measured); S.measuredFrames = await decode(D.measured_frames);
    S.first = S.measuredFrames[0]; S.last = S.measuredFrames[S.measuredFrames.length - 1];
    const scrub = $("scrub"); scrub.min = String(S.first); scrub.max = String(S.last);
    S.row = S.first;
    readHash();
    if (D.audio) $("audio").src = D.audio;
    const kept = "every " + D.stride + "th recording row and every frame a check points at";
    $("prev").title = "the previous kept frame (" + kept + ")";
    $("next").title = "the next kept frame (" + kept + ")";
    initThree();
    TL.width = Math.max(320, Math.round(TL.clientWidth));
    await setVersions();
    window.addEventListener("hashchange", () => followHash().catch(fail));
    va.addEventListener("change", () => setVersions().catch(fail));
    vb.addEventListener("change", () => setVersions().catch(fail));
    $("mode").addEventListener("change", () => setVersions().catch(fail));
    document.querySelectorAll("button[data-view]").forEach((btn) => btn.addEventListener("click", () => setView(btn.dataset.view)));
    $("play").addEventListener("click", () => (S.playing ? pause() : play()));
    $("next").addEventListener("click", () => stepKept(1));
    $("prev").addEventListener("click", () => stepKept(-1));
    $("speed").addEventListener("change", () => { S.speed = Number($("speed").value); if (S.playing) { pause(); play(); } });
    $("pellet").addEventListener("change", () => { S.pellet = Number($("pellet").value); drawTimeline(); });
    scrub.addEventListener("input", () => { pause(); go(Number(scrub.value)); });
    TL.addEventListener("click", (ev) => { pause(); const r = TL.getBoundingClientRect(); go(rowOf((ev.clientX - r.left) * TL.width / r.width)); });
    $("pellets").addEventListener("change", () => setPellets($("pellets").checked));
    $("helpbtn").addEventListener("click", () => toggleHelp());
    // the keys the help lists (#help); a change here belongs there too
    document.addEventListener("keydown", (ev) => {
      if (ev.key === "Escape") { toggleHelp(false); return; }
      if (ev.target.tagName === "SELECT" || ev.target.tagName === "INPUT" || ev.ctrlKey || ev.metaKey || ev.altKey) return;
      if (ev.key === " ") { ev.preventDefault(); S.playing ? pause() : play(); }
      if (ev.key === "ArrowRight") stepKept(1);
      if (ev.key === "ArrowLeft") stepKept(-1);
      if (ev.key === "p" || ev.key === "P") { if (pelletsA) setPellets(!S.pellets); }
      if (ev.key === "?") toggleHelp();
    });
    status.textContent = "ready"; status.dataset.ready = "1";
    // for tests and the console: the state, where the camera is, what the 3D view and the timeline draw
    const vec = (m) => (m.visible ? m.position.toArray() : null);
    window.cassiViewer = { state: S, go: go, setView: setView, three: () => ({ camera, sceneA, renderer }),
                           camera: () => ({ position: camera.position.toArray(), up: camera.up.toArray(),
                                            target: controls.target.toArray() }),
                           pellets: () => [pelletsA, pelletsB].map((m) => m && S.pellets
                             ? { version: m.ver.name, measured: m.measured.map(vec), model: m.model.map(vec) } : null),
                           diff: () => (S.diff ? { top: S.diff.top, frameMax: S.diff.frameMax, mm: Array.from(S.diff.mm) }
                                                : { why: S.diffWhy }),
                           timeline: () => ({ lanes: LANES, ticks: timeTicks(), x: (row) => xOf(row),
                                              width: TL.width, height: TL.height }) };
  }
  if (!D) fail("no viewer data (the task's .js file did not load)");
  else start().catch(fail);
})();
