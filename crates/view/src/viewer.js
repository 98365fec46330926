// rdt-mesher mesh viewer (ours): draws the inlined mesh with WebGL, or with a 2D canvas where
// WebGL is missing. No network: everything it needs is in this page.
// URL hash: #color=KEY&edges=0|1&fail=0|1&renderer=webgl|2d&yaw=DEG&pitch=DEG&zoom=F
(function () {
  "use strict";
  var D = JSON.parse(document.getElementById("mesh-data").textContent);

  function b64(s, Type) {
    var bin = atob(s), n = bin.length, u = new Uint8Array(n);
    for (var i = 0; i < n; i++) u[i] = bin.charCodeAt(i);
    return new Type(u.buffer);
  }
  var pos = b64(D.positions, Float32Array);
  var tri = b64(D.triangles, Uint32Array);
  var nt = tri.length / 3;
  D.measures.forEach(function (m) { m.data = b64(m.values, Float32Array); });
  var high = new Uint8Array(nt);
  D.highlights.forEach(function (h) { h.facets.forEach(function (f) { high[f] = 1; }); });

  // Facet normals (for shading) and unique edges.
  var fnorm = new Float32Array(3 * nt);
  for (var f = 0; f < nt; f++) {
    var a = 3 * tri[3 * f], b = 3 * tri[3 * f + 1], c = 3 * tri[3 * f + 2];
    var ux = pos[b] - pos[a], uy = pos[b + 1] - pos[a + 1], uz = pos[b + 2] - pos[a + 2];
    var vx = pos[c] - pos[a], vy = pos[c + 1] - pos[a + 1], vz = pos[c + 2] - pos[a + 2];
    var nx = uy * vz - uz * vy, ny = uz * vx - ux * vz, nz = ux * vy - uy * vx;
    var l = Math.sqrt(nx * nx + ny * ny + nz * nz) || 1;
    fnorm[3 * f] = nx / l; fnorm[3 * f + 1] = ny / l; fnorm[3 * f + 2] = nz / l;
  }
  var edgeSet = {}, edges = [];
  for (var f2 = 0; f2 < nt; f2++) {
    for (var k = 0; k < 3; k++) {
      var p = tri[3 * f2 + k], q = tri[3 * f2 + (k + 1) % 3];
      var key = p < q ? p + "," + q : q + "," + p;
      if (!edgeSet[key]) { edgeSet[key] = 1; edges.push(p, q); }
    }
  }

  var state = { color: D.default_measure, edges: D.edges_default, fail: true, renderer: "webgl",
                yaw: -30, pitch: 20, zoom: 1 };
  function readHash() {
    var h = location.hash.replace(/^#/, "");
    h.split("&").forEach(function (kv) {
      var i = kv.indexOf("="); if (i < 0) return;
      var k = decodeURIComponent(kv.slice(0, i)), v = decodeURIComponent(kv.slice(i + 1));
      if (k === "color" && D.measures.some(function (m) { return m.key === v; })) state.color = v;
      if (k === "edges") state.edges = v === "1";
      if (k === "fail") state.fail = v === "1";
      if (k === "renderer") state.renderer = v;
      if (k === "yaw" || k === "pitch" || k === "zoom") { var x = parseFloat(v); if (isFinite(x)) state[k] = x; }
    });
  }
  readHash();

  function measure() {
    for (var i = 0; i < D.measures.length; i++) if (D.measures[i].key === state.color) return D.measures[i];
    return D.measures[0];
  }
  function range(m) {
    var lo = Infinity, hi = -Infinity;
    for (var i = 0; i < m.data.length; i++) { var v = m.data[i]; if (isFinite(v)) { if (v < lo) lo = v; if (v > hi) hi = v; } }
    return lo <= hi ? [lo, hi] : null;
  }
  function seq(t) {
    var P = D.palette.sequential, x = Math.min(Math.max(t, 0), 1) * (P.length - 1);
    var i = Math.min(Math.floor(x), P.length - 2), g = x - i;
    return [0, 1, 2].map(function (k) { return P[i][k] + g * (P[i + 1][k] - P[i][k]); });
  }
  function facetColors() {
    var m = measure(), r = range(m), out = new Float32Array(3 * nt);
    for (var f = 0; f < nt; f++) {
      var v = m.data[f], c;
      if (state.fail && high[f]) c = D.palette.highlight;
      else if (!isFinite(v)) c = D.palette.unknown;
      else if (m.categorical) c = D.palette.categorical[Math.max(0, v | 0) % D.palette.categorical.length];
      else c = seq(r && r[1] > r[0] ? (v - r[0]) / (r[1] - r[0]) : 0.5);
      out[3 * f] = c[0] / 255; out[3 * f + 1] = c[1] / 255; out[3 * f + 2] = c[2] / 255;
    }
    return out;
  }

  // World to camera: the front view (right, up, toward), then the user's yaw and pitch.
  function rotation() {
    var B = D.view; // rows: right, up, toward
    var cy = Math.cos(state.yaw * Math.PI / 180), sy = Math.sin(state.yaw * Math.PI / 180);
    var cp = Math.cos(state.pitch * Math.PI / 180), sp = Math.sin(state.pitch * Math.PI / 180);
    var Y = [[cy, 0, sy], [0, 1, 0], [-sy, 0, cy]], X = [[1, 0, 0], [0, cp, -sp], [0, sp, cp]];
    function mul(A, C) {
      return [0, 1, 2].map(function (i) { return [0, 1, 2].map(function (j) {
        return A[i][0] * C[0][j] + A[i][1] * C[1][j] + A[i][2] * C[2][j]; }); });
    }
    return mul(X, mul(Y, B));
  }
  var LIGHT = (function () { var l = [-0.3, 0.5, 1.0], n = Math.hypot(l[0], l[1], l[2]); return l.map(function (x) { return x / n; }); })();

  var canvas = document.getElementById("view");
  function resize() {
    var r = canvas.getBoundingClientRect(), dpr = window.devicePixelRatio || 1;
    canvas.width = Math.max(1, Math.round(r.width * dpr));
    canvas.height = Math.max(1, Math.round(r.height * dpr));
  }
  resize();
  function scales() {
    var w = canvas.width, h = canvas.height, s = 0.95 * state.zoom;
    return w > h ? [s * h / w, s] : [s, s * w / h];
  }

  // ---- WebGL ----
  function makeWebGL() {
    var gl = null;
    try { gl = canvas.getContext("webgl", { preserveDrawingBuffer: true, antialias: true }); } catch (e) { gl = null; }
    if (!gl) return null;
    function prog(vs, fs) {
      function sh(type, src) {
        var s = gl.createShader(type); gl.shaderSource(s, src); gl.compileShader(s);
        if (!gl.getShaderParameter(s, gl.COMPILE_STATUS)) throw new Error(gl.getShaderInfoLog(s));
        return s;
      }
      var p = gl.createProgram();
      gl.attachShader(p, sh(gl.VERTEX_SHADER, vs)); gl.attachShader(p, sh(gl.FRAGMENT_SHADER, fs));
      gl.linkProgram(p);
      if (!gl.getProgramParameter(p, gl.LINK_STATUS)) throw new Error(gl.getProgramInfoLog(p));
      return p;
    }
    var head = "uniform mat3 rot; uniform vec2 scale; attribute vec3 p;" +
      "vec4 place(vec3 q) { vec3 r = rot * q; return vec4(r.x * scale.x, r.y * scale.y, -0.9 * r.z, 1.0); }";
    var tp = prog(head + "attribute vec3 n; attribute vec3 c; uniform vec3 light; varying vec3 vc;" +
      "void main() { gl_Position = place(p); float k = 0.3 + 0.7 * abs(dot(normalize(rot * n), light)); vc = c * k; }",
      "precision mediump float; varying vec3 vc; void main() { gl_FragColor = vec4(vc, 1.0); }");
    var lp = prog(head + "void main() { gl_Position = place(p); gl_Position.z -= 0.004; }",
      "precision mediump float; uniform vec3 ink; void main() { gl_FragColor = vec4(ink, 1.0); }");
    var P = new Float32Array(9 * nt), N = new Float32Array(9 * nt);
    for (var f = 0; f < nt; f++) for (var k = 0; k < 3; k++) {
      var v = tri[3 * f + k];
      for (var j = 0; j < 3; j++) { P[9 * f + 3 * k + j] = pos[3 * v + j]; N[9 * f + 3 * k + j] = fnorm[3 * f + j]; }
    }
    var E = new Float32Array(3 * edges.length);
    for (var e = 0; e < edges.length; e++) for (var j2 = 0; j2 < 3; j2++) E[3 * e + j2] = pos[3 * edges[e] + j2];
    function buf(data) { var b = gl.createBuffer(); gl.bindBuffer(gl.ARRAY_BUFFER, b); gl.bufferData(gl.ARRAY_BUFFER, data, gl.STATIC_DRAW); return b; }
    var bp = buf(P), bn = buf(N), bc = buf(new Float32Array(9 * nt)), be = buf(E);
    function attr(program, name, b) {
      var loc = gl.getAttribLocation(program, name); if (loc < 0) return;
      gl.bindBuffer(gl.ARRAY_BUFFER, b); gl.enableVertexAttribArray(loc);
      gl.vertexAttribPointer(loc, 3, gl.FLOAT, false, 0, 0);
    }
    return {
      name: "webgl",
      setColors: function (fc) {
        var C = new Float32Array(9 * nt);
        for (var f = 0; f < nt; f++) for (var k = 0; k < 3; k++) for (var j = 0; j < 3; j++) C[9 * f + 3 * k + j] = fc[3 * f + j];
        gl.bindBuffer(gl.ARRAY_BUFFER, bc); gl.bufferData(gl.ARRAY_BUFFER, C, gl.DYNAMIC_DRAW);
      },
      draw: function () {
        var R = rotation(), s = scales();
        var m = [R[0][0], R[1][0], R[2][0], R[0][1], R[1][1], R[2][1], R[0][2], R[1][2], R[2][2]];
        gl.viewport(0, 0, canvas.width, canvas.height);
        var bg = D.palette.background;
        gl.clearColor(bg[0] / 255, bg[1] / 255, bg[2] / 255, 1);
        gl.clear(gl.COLOR_BUFFER_BIT | gl.DEPTH_BUFFER_BIT);
        gl.enable(gl.DEPTH_TEST);
        gl.enable(gl.POLYGON_OFFSET_FILL); gl.polygonOffset(1, 1);
        gl.useProgram(tp);
        gl.uniformMatrix3fv(gl.getUniformLocation(tp, "rot"), false, m);
        gl.uniform2f(gl.getUniformLocation(tp, "scale"), s[0], s[1]);
        gl.uniform3f(gl.getUniformLocation(tp, "light"), LIGHT[0], LIGHT[1], LIGHT[2]);
        attr(tp, "p", bp); attr(tp, "n", bn); attr(tp, "c", bc);
        gl.drawArrays(gl.TRIANGLES, 0, 3 * nt);
        for (var i = 0; i < 3; i++) gl.disableVertexAttribArray(i);
        if (state.edges) {
          gl.useProgram(lp);
          gl.uniformMatrix3fv(gl.getUniformLocation(lp, "rot"), false, m);
          gl.uniform2f(gl.getUniformLocation(lp, "scale"), s[0], s[1]);
          gl.uniform3f(gl.getUniformLocation(lp, "ink"), 0.08, 0.08, 0.08);
          attr(lp, "p", be);
          gl.drawArrays(gl.LINES, 0, edges.length);
          gl.disableVertexAttribArray(gl.getAttribLocation(lp, "p"));
        }
      }
    };
  }

  // ---- 2D canvas: painter's order by facet depth ----
  function make2D() {
    var ctx = canvas.getContext("2d");
    var colors = null;
    return {
      name: "2d",
      setColors: function (fc) { colors = fc; },
      draw: function () {
        var R = rotation(), s = scales(), w = canvas.width, h = canvas.height, nv = pos.length / 3;
        var X = new Float32Array(nv), Y = new Float32Array(nv), Z = new Float32Array(nv);
        for (var v = 0; v < nv; v++) {
          var x = pos[3 * v], y = pos[3 * v + 1], z = pos[3 * v + 2];
          X[v] = (1 + s[0] * (R[0][0] * x + R[0][1] * y + R[0][2] * z)) * w / 2;
          Y[v] = (1 - s[1] * (R[1][0] * x + R[1][1] * y + R[1][2] * z)) * h / 2;
          Z[v] = R[2][0] * x + R[2][1] * y + R[2][2] * z;
        }
        var order = new Array(nt), depth = new Float32Array(nt);
        for (var f = 0; f < nt; f++) { order[f] = f; depth[f] = Z[tri[3 * f]] + Z[tri[3 * f + 1]] + Z[tri[3 * f + 2]]; }
        order.sort(function (a, b) { return depth[a] - depth[b] || a - b; });
        var bg = D.palette.background;
        ctx.fillStyle = "rgb(" + bg.join(",") + ")"; ctx.fillRect(0, 0, w, h);
        ctx.lineJoin = "round";
        for (var i = 0; i < nt; i++) {
          var g = order[i], a = tri[3 * g], b = tri[3 * g + 1], c = tri[3 * g + 2];
          var n = fnorm.subarray(3 * g, 3 * g + 3);
          var nz = [0, 1, 2].map(function (r) { return R[r][0] * n[0] + R[r][1] * n[1] + R[r][2] * n[2]; });
          var k = 0.3 + 0.7 * Math.abs(nz[0] * LIGHT[0] + nz[1] * LIGHT[1] + nz[2] * LIGHT[2]);
          var col = "rgb(" + [0, 1, 2].map(function (j) { return Math.round(255 * colors[3 * g + j] * k); }).join(",") + ")";
          ctx.beginPath(); ctx.moveTo(X[a], Y[a]); ctx.lineTo(X[b], Y[b]); ctx.lineTo(X[c], Y[c]); ctx.closePath();
          ctx.fillStyle = col; ctx.fill();
          ctx.strokeStyle = state.edges ? "rgb(20,20,20)" : col; ctx.lineWidth = state.edges ? 1 : 0.6; ctx.stroke();
        }
      }
    };
  }

  var R = null;
  if (state.renderer !== "2d") { try { R = makeWebGL(); } catch (e) { R = null; } }
  if (!R) R = make2D();
  document.getElementById("renderer").textContent = R.name;

  // ---- panel: controls, colour bar, summary, checks, certificate ----
  function el(tag, attrs, text) {
    var e = document.createElement(tag);
    for (var k in attrs) e.setAttribute(k, attrs[k]);
    if (text !== undefined) e.textContent = text;
    return e;
  }
  var sel = document.getElementById("color");
  D.measures.forEach(function (m) {
    var known = range(m) !== null;
    var o = el("option", { value: m.key }, m.label + (known ? "" : " (not known)"));
    if (!known) o.disabled = true;
    sel.appendChild(o);
  });
  var cbEdges = document.getElementById("edges"), cbFail = document.getElementById("fail");
  function legend() {
    var m = measure(), r = range(m), box = document.getElementById("legend");
    box.innerHTML = "";
    if (m.categorical) {
      var count = r ? r[1] + 1 : 0;
      for (var i = 0; i < Math.min(count, 8); i++) {
        var c = D.palette.categorical[i % D.palette.categorical.length];
        var row = el("div", {}, ""); row.appendChild(el("span", { "class": "sw", style: "background:rgb(" + c.join(",") + ")" }));
        row.appendChild(document.createTextNode(" component " + i)); box.appendChild(row);
      }
      if (count > 8) box.appendChild(el("div", {}, count + " components (colours repeat)"));
    } else if (r) {
      var stops = D.palette.sequential.map(function (c, i) { return "rgb(" + c.join(",") + ") " + (100 * i / (D.palette.sequential.length - 1)) + "%"; });
      box.appendChild(el("div", { "class": "bar", style: "background:linear-gradient(to right," + stops.join(",") + ")" }));
      var lab = el("div", { "class": "barlab" });
      lab.appendChild(el("span", {}, r[0].toPrecision(4))); lab.appendChild(el("span", {}, r[1].toPrecision(4)));
      box.appendChild(lab);
      if (m.bound !== null) box.appendChild(el("div", {}, "bound " + m.bound));
    }
    var nh = 0; for (var f = 0; f < nt; f++) nh += high[f];
    var hl = el("div", {}, ""); hl.appendChild(el("span", { "class": "sw", style: "background:rgb(" + D.palette.highlight.join(",") + ")" }));
    hl.appendChild(document.createTextNode(" " + nh + " facets behind a FAIL or an unmet criterion"));
    box.appendChild(hl);
    D.highlights.forEach(function (h) { box.appendChild(el("div", { "class": "small" }, h.facets.length + ": " + h.reason)); });
  }
  function apply() {
    sel.value = state.color; cbEdges.checked = state.edges; cbFail.checked = state.fail;
    R.setColors(facetColors()); legend(); R.draw();
  }
  sel.onchange = function () { state.color = sel.value; apply(); };
  cbEdges.onchange = function () { state.edges = cbEdges.checked; apply(); };
  cbFail.onchange = function () { state.fail = cbFail.checked; apply(); };
  document.getElementById("reset").onclick = function () { state.yaw = -30; state.pitch = 20; state.zoom = 1; R.draw(); };
  window.addEventListener("hashchange", function () { readHash(); apply(); });
  window.addEventListener("resize", function () { resize(); R.draw(); });
  var drag = null;
  canvas.addEventListener("mousedown", function (e) { drag = [e.clientX, e.clientY]; });
  window.addEventListener("mouseup", function () { drag = null; });
  window.addEventListener("mousemove", function (e) {
    if (!drag) return;
    state.yaw += (e.clientX - drag[0]) * 0.5; state.pitch += (e.clientY - drag[1]) * 0.5;
    state.pitch = Math.max(-90, Math.min(90, state.pitch)); drag = [e.clientX, e.clientY]; R.draw();
  });
  canvas.addEventListener("wheel", function (e) {
    e.preventDefault(); state.zoom *= Math.exp(-e.deltaY * 0.001);
    state.zoom = Math.max(0.1, Math.min(50, state.zoom)); R.draw();
  }, { passive: false });

  document.getElementById("title").textContent = D.title;
  var sum = document.getElementById("summary");
  D.summary.forEach(function (l) { sum.appendChild(el("div", {}, l)); });
  var rep = D.report || {};
  var ver = rep.verify || rep;
  var checks = (ver && ver.checks) || [];
  var tb = document.getElementById("checks");
  checks.forEach(function (c) {
    var tr = el("tr", { "class": c.status });
    tr.appendChild(el("td", {}, c.status)); tr.appendChild(el("td", {}, c.name)); tr.appendChild(el("td", {}, c.detail));
    tb.appendChild(tr);
  });
  var cert = ver && ver.certificate, cd = document.getElementById("certificate");
  if (cert) {
    ["eps_achieved", "requested_eps", "exceeding_total", "worst_facet", "balls", "facets_without_ball", "dm_source"].forEach(function (k) {
      if (cert[k] !== undefined && cert[k] !== null) cd.appendChild(el("div", {}, k + ": " + cert[k]));
    });
  } else cd.textContent = "no certificate in the report (the loose-epsilon check below says why)";
  apply();
  // What the page fetched besides itself (the tests read it; it stays empty: no network).
  var fetched = (window.performance && performance.getEntriesByType) ? performance.getEntriesByType("resource") : [];
  document.getElementById("fetched").textContent = fetched.length + (fetched.length ? ": " + fetched.map(function (r) { return r.name; }).join(" ") : "");
})();
