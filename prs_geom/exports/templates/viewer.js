(function () {
  const errs = [];
  window.addEventListener('error', function (e) {
    errs.push(String(e.message));
    document.body.dataset.errors = String(errs.length);
    const el = document.getElementById('errors');
    if (el) { el.textContent = errs.join('\n'); el.style.display = 'block'; }
  });
  function decode(b64, Type) {
    const bin = atob(b64); const buf = new ArrayBuffer(bin.length); const u8 = new Uint8Array(buf);
    for (let i = 0; i < bin.length; i++) u8[i] = bin.charCodeAt(i);
    return new Type(buf);
  }
  function hex(c) { return [parseInt(c.slice(1, 3), 16), parseInt(c.slice(3, 5), 16), parseInt(c.slice(5, 7), 16)]; }
  const data = JSON.parse(document.getElementById('scene-data').textContent);
  const meshes = data.meshes.map(m => ({ v: decode(m.v, Float32Array), f: decode(m.f, Uint32Array) }));
  let nTri = 0;
  for (const inst of data.instances) nTri += meshes[inst.mesh].f.length / 3;
  const P = new Float32Array(nTri * 9), N = new Float32Array(nTri * 3), C = new Uint8Array(nTri * 3);
  const CUT = new Uint8Array(nTri);
  let t = 0; const lo = [1e9, 1e9, 1e9], hi = [-1e9, -1e9, -1e9];
  for (const inst of data.instances) {
    const m = meshes[inst.mesh], T = inst.T, col = hex(inst.colour);
    for (let k = 0; k < m.f.length; k += 3, t++) {
      const q = [];
      for (let c = 0; c < 3; c++) {
        const i = m.f[k + c] * 3, x = m.v[i], y = m.v[i + 1], z = m.v[i + 2];
        const w = [T[0] * x + T[1] * y + T[2] * z + T[3], T[4] * x + T[5] * y + T[6] * z + T[7],
                   T[8] * x + T[9] * y + T[10] * z + T[11]];
        for (let d = 0; d < 3; d++) { P[t * 9 + c * 3 + d] = w[d]; lo[d] = Math.min(lo[d], w[d]); hi[d] = Math.max(hi[d], w[d]); }
        q.push(w);
      }
      const ux = q[1][0] - q[0][0], uy = q[1][1] - q[0][1], uz = q[1][2] - q[0][2];
      const vx = q[2][0] - q[0][0], vy = q[2][1] - q[0][1], vz = q[2][2] - q[0][2];
      let nx = uy * vz - uz * vy, ny = uz * vx - ux * vz, nz = ux * vy - uy * vx;
      const len = Math.hypot(nx, ny, nz) || 1;
      N[t * 3] = nx / len; N[t * 3 + 1] = ny / len; N[t * 3 + 2] = nz / len;
      C[t * 3] = col[0]; C[t * 3 + 1] = col[1]; C[t * 3 + 2] = col[2];
      CUT[t] = inst.cut ? 1 : 0;
    }
  }
  const centre = [0.5 * (lo[0] + hi[0]), 0.5 * (lo[1] + hi[1]), 0.5 * (lo[2] + hi[2])];
  // the bounding box's diagonal: the assembly's projection fits it at every rotation
  const span = Math.hypot(hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]);
  const canvas = document.getElementById('view'), ctx = canvas.getContext('2d');
  let yaw = 0.6, pitch = -1.2, zoom = 1.0;
  const depth = new Float32Array(nTri), order = new Uint32Array(nTri), X = new Float32Array(nTri * 6);
  function draw() {
    const W = canvas.width, H = canvas.height, s = zoom * 0.96 * Math.min(W, H) / span;
    const cy = Math.cos(yaw), sy = Math.sin(yaw), cp = Math.cos(pitch), sp = Math.sin(pitch);
    // rotation: yaw about z, then pitch about x (view looks along -z of the rotated frame)
    const R = [cy, -sy, 0, cp * sy, cp * cy, -sp, sp * sy, sp * cy, cp];
    ctx.fillStyle = '#f4f6f8'; ctx.fillRect(0, 0, W, H);
    let n = 0;
    const cut = document.getElementById('cutaway').checked;
    for (let i = 0; i < nTri; i++) {
      const nzv = R[6] * N[i * 3] + R[7] * N[i * 3 + 1] + R[8] * N[i * 3 + 2];
      if (CUT[i] && cut) {
        // cutaway: drop the nut's half nearer to the viewer (centroid in front of the axis)
        const gx = (P[i * 9] + P[i * 9 + 3] + P[i * 9 + 6]) / 3 - centre[0];
        const gy = (P[i * 9 + 1] + P[i * 9 + 4] + P[i * 9 + 7]) / 3 - centre[1];
        if (R[6] * gx + R[7] * gy > 0) continue;
      } else if (nzv <= 0) continue;
      let zsum = 0;
      for (let c = 0; c < 3; c++) {
        const x = P[i * 9 + c * 3] - centre[0], y = P[i * 9 + c * 3 + 1] - centre[1], z = P[i * 9 + c * 3 + 2] - centre[2];
        X[i * 6 + c * 2] = W / 2 + s * (R[0] * x + R[1] * y + R[2] * z);
        X[i * 6 + c * 2 + 1] = H / 2 - s * (R[3] * x + R[4] * y + R[5] * z);
        zsum += R[6] * x + R[7] * y + R[8] * z;
      }
      depth[i] = zsum; order[n++] = i;
    }
    const vis = order.subarray(0, n);
    vis.sort((a, b) => depth[a] - depth[b]);
    for (let k = 0; k < n; k++) {
      const i = vis[k];
      const nzv = R[6] * N[i * 3] + R[7] * N[i * 3 + 1] + R[8] * N[i * 3 + 2];
      const l = 0.35 + 0.65 * Math.abs(nzv);
      const col = 'rgb(' + (C[i * 3] * l | 0) + ',' + (C[i * 3 + 1] * l | 0) + ',' + (C[i * 3 + 2] * l | 0) + ')';
      ctx.fillStyle = col; ctx.strokeStyle = col; ctx.lineWidth = 0.5;
      ctx.beginPath();
      ctx.moveTo(X[i * 6], X[i * 6 + 1]); ctx.lineTo(X[i * 6 + 2], X[i * 6 + 3]); ctx.lineTo(X[i * 6 + 4], X[i * 6 + 5]);
      ctx.closePath(); ctx.fill(); ctx.stroke();
    }
    // self-check for the browser tests: model pixels on the canvas border mean clipping;
    // coverage = share of the canvas the parts cover (sampled every 4th pixel)
    const img = ctx.getImageData(0, 0, W, H).data;
    const bg = (o) => Math.abs(img[o] - 0xf4) + Math.abs(img[o + 1] - 0xf6) + Math.abs(img[o + 2] - 0xf8) < 12;
    let edge = 0, cover = 0, total = 0;
    for (let x = 0; x < W; x++) { if (!bg(4 * x)) edge++; if (!bg(4 * ((H - 1) * W + x))) edge++; }
    for (let y = 0; y < H; y++) { if (!bg(4 * y * W)) edge++; if (!bg(4 * (y * W + W - 1))) edge++; }
    for (let y = 0; y < H; y += 4) for (let x = 0; x < W; x += 4) { total++; if (!bg(4 * (y * W + x))) cover++; }
    document.body.dataset.edgePixels = String(edge);
    document.body.dataset.coverage = (cover / total).toFixed(3);
    document.body.dataset.canvas = W + 'x' + H;
    document.getElementById('viewinfo').textContent =
      nTri + ' triangles (' + n + ' facing the viewer), display tolerance ' + data.tolerance_mm + ' mm. Drag to rotate, wheel to zoom.';
  }
  let dragging = false, lx = 0, ly = 0, pending = false;
  function later() { if (!pending) { pending = true; requestAnimationFrame(() => { pending = false; draw(); }); } }
  canvas.addEventListener('mousedown', e => { dragging = true; lx = e.clientX; ly = e.clientY; });
  window.addEventListener('mouseup', () => { dragging = false; });
  window.addEventListener('mousemove', e => {
    if (!dragging) return;
    yaw += 0.01 * (e.clientX - lx); pitch += 0.01 * (e.clientY - ly); lx = e.clientX; ly = e.clientY; later();
  });
  document.getElementById('cutaway').addEventListener('change', later);
  canvas.addEventListener('wheel', e => { e.preventDefault(); zoom *= Math.exp(-0.001 * e.deltaY); later(); }, { passive: false });
  // the canvas follows the page width (at most its 900 px design width), keeping its aspect
  function resize() {
    const w = Math.max(200, Math.min(900, Math.floor(canvas.parentElement.clientWidth || 900)));
    const h = Math.round(w * 560 / 900);
    if (canvas.width !== w || canvas.height !== h) { canvas.width = w; canvas.height = h; }
    draw();
  }
  window.addEventListener('resize', resize);
  resize();
  document.body.dataset.triangles = String(nTri);
  document.body.dataset.viewer = 'ok';
})();
