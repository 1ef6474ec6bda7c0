// report.html 3D view: three.js (WebGL, depth-buffered) on the embedded scene data.
// Frames: the data are in the screw frame, z along the screw axis, mm; the view lays the axis
// horizontal along three.js's x (y up), as a drawing does: a long actuator screw then fills the
// landscape canvas. One BufferGeometry per distinct part mesh, one Mesh per placed part
// (the rollers share one geometry). Drag to rotate, wheel to zoom, right-drag to pan.
import * as THREE from 'three';
import { OrbitControls } from 'three/addons/controls/OrbitControls.js';

const BACKGROUND = 0xf4f6f8;
const data = JSON.parse(document.getElementById('scene-data').textContent);

function decode(b64, Type) {
  const bin = atob(b64); const u8 = new Uint8Array(bin.length);
  for (let i = 0; i < bin.length; i++) u8[i] = bin.charCodeAt(i);
  return new Type(u8.buffer);
}

const canvas = document.getElementById('view');
let renderer;
try {
  renderer = new THREE.WebGLRenderer({ canvas, antialias: true, preserveDrawingBuffer: true });
} catch (e) {
  document.body.dataset.viewer = 'no-webgl';
  document.getElementById('viewinfo').textContent =
    'This browser offers no WebGL, so the 3D view cannot be drawn (the tables below are complete).';
  throw e;
}
renderer.localClippingEnabled = true;
const scene = new THREE.Scene();
scene.background = new THREE.Color(BACKGROUND);
const root = new THREE.Group();
root.rotation.y = Math.PI / 2;               // the screw axis (z) horizontal, along three.js x
scene.add(root);

const geometries = data.meshes.map(m => {
  const g = new THREE.BufferGeometry();
  g.setAttribute('position', new THREE.BufferAttribute(decode(m.v, Float32Array), 3));
  g.setIndex(new THREE.BufferAttribute(decode(m.f, Uint32Array), 1));
  g.computeBoundingBox();
  return g;
});
// the nut is cut open by a plane through the axis facing the camera
const cutPlane = new THREE.Plane(new THREE.Vector3(1, 0, 0), 0);
const materials = {};
function material(colour, cut) {
  const key = colour + (cut ? ':cut' : '');
  if (!materials[key]) {
    materials[key] = new THREE.MeshStandardMaterial({
      color: new THREE.Color(colour), metalness: 0.35, roughness: 0.45, flatShading: true,
      side: cut ? THREE.DoubleSide : THREE.FrontSide, clippingPlanes: cut ? [cutPlane] : [],
    });
  }
  return materials[key];
}
let nTri = 0;
const box = new THREE.Box3();
const placed = [];                            // [mesh, rest matrix, moving body] per part
for (const inst of data.instances) {
  const g = geometries[inst.mesh];
  const mesh = new THREE.Mesh(g, material(inst.colour, inst.cut));
  mesh.name = inst.name;
  mesh.matrixAutoUpdate = false;
  const T = inst.T;
  mesh.matrix.set(T[0], T[1], T[2], T[3], T[4], T[5], T[6], T[7], T[8], T[9], T[10], T[11],
                  T[12], T[13], T[14], T[15]);
  placed.push([mesh, mesh.matrix.clone(), inst.motion]);
  root.add(mesh);
  nTri += g.index.count / 3;
}
// the running mechanism: per moving body its motion M(t) at keys over one screw revolution
// (row-major 4x4, world = M(t) rest); drawn at the nearest key, as the keys are 5 deg apart
const playBox = document.getElementById('play');   // absent on pages without the control
const anim = data.animation && playBox ? data.animation : null;
const motions = {};
if (anim) {
  for (const [body, b64] of Object.entries(anim.motions)) motions[body] = decode(b64, Float32Array);
  document.getElementById('play-label').hidden = false;
}
function pose(t) {
  const key = Math.round(((t / anim.period_s) % 1) * (anim.keys - 1));
  const M = new THREE.Matrix4();
  for (const [mesh, rest, body] of placed) {
    const m = motions[body];
    if (!m) continue;
    const o = 16 * key;
    M.set(m[o], m[o + 1], m[o + 2], m[o + 3], m[o + 4], m[o + 5], m[o + 6], m[o + 7],
          m[o + 8], m[o + 9], m[o + 10], m[o + 11], m[o + 12], m[o + 13], m[o + 14], m[o + 15]);
    mesh.matrix.multiplyMatrices(M, rest);
  }
  root.updateMatrixWorld(true);
  document.body.dataset.animationKey = String(key);
}
root.updateMatrixWorld(true);
box.setFromObject(root);
const sphere = box.getBoundingSphere(new THREE.Sphere());

const camera = new THREE.PerspectiveCamera(30, 900 / 560, 0.01 * sphere.radius, 100 * sphere.radius);
scene.add(camera);
scene.add(new THREE.HemisphereLight(0xffffff, 0x8090a0, 1.6));
const key = new THREE.DirectionalLight(0xffffff, 2.2);
key.position.set(1, 1.5, 2);
camera.add(key);                              // the light follows the view
const controls = new OrbitControls(camera, canvas);
controls.target.copy(sphere.center);

// the camera distance at which the view fits both the height and the width: a docs picture's
// view scales the bounding sphere by its fit; by default every corner of the bounding box
// projects inside the view with 4 % to spare (a long actuator screw would leave most of a
// sphere's view empty)
function fitDistance() {
  const half = THREE.MathUtils.degToRad(camera.fov / 2);
  if (data.view && data.view.fit) {
    const halfH = Math.atan(Math.tan(half) * Math.min(1, camera.aspect));
    return data.view.fit * sphere.radius / Math.sin(halfH);
  }
  const tanV = Math.tan(half), tanH = tanV * camera.aspect;
  const right = new THREE.Vector3().crossVectors(new THREE.Vector3(0, 1, 0), viewDir).normalize();
  const up = new THREE.Vector3().crossVectors(viewDir, right);
  let d = 0;
  for (let i = 0; i < 8; i++) {
    const c = new THREE.Vector3(i & 1 ? box.max.x : box.min.x, i & 2 ? box.max.y : box.min.y,
                                i & 4 ? box.max.z : box.min.z).sub(sphere.center);
    const z = c.dot(viewDir);
    d = Math.max(d, z + Math.abs(c.dot(right)) / tanH, z + Math.abs(c.dot(up)) / tanV);
  }
  return 1.04 * d;
}
// optional view in the scene data (docs pictures): direction from the target, y up
const viewDir = (data.view && data.view.direction ? new THREE.Vector3(...data.view.direction)
                 : new THREE.Vector3(0.55, 0.45, 1.0)).normalize();
camera.position.copy(sphere.center).addScaledVector(viewDir, fitDistance());
controls.update();

function updateCut() {
  const cut = document.getElementById('cutaway').checked;
  // normal from the camera to the axis, square to it: the half nearer to the viewer is clipped
  const n = new THREE.Vector3().subVectors(sphere.center, camera.position);
  n.x = 0;
  if (n.lengthSq() < 1e-12) n.set(0, 0, -1);
  n.normalize();
  cutPlane.normal.copy(n);
  cutPlane.constant = -n.dot(sphere.center);
  for (const m of Object.values(materials)) {
    if (m.side === THREE.DoubleSide) m.clippingPlanes = cut ? [cutPlane] : [];
  }
}

// self-check for the browser tests: model pixels on the canvas border mean clipping;
// coverage = share of the canvas the parts cover (every 4th pixel); renderer = the WebGL
// version drawing (occlusion per pixel by the depth buffer, no painter's sort)
function selfCheck() {
  const gl = renderer.getContext();
  const W = gl.drawingBufferWidth, H = gl.drawingBufferHeight;
  const px = new Uint8Array(W * H * 4);
  gl.readPixels(0, 0, W, H, gl.RGBA, gl.UNSIGNED_BYTE, px);
  // the background as written to the sRGB canvas (THREE.Color would hold it linearised)
  const br = (BACKGROUND >> 16) & 255, bgg = (BACKGROUND >> 8) & 255, bb = BACKGROUND & 255;
  const bg = (x, y) => {
    const o = 4 * (y * W + x);
    return Math.abs(px[o] - br) + Math.abs(px[o + 1] - bgg) + Math.abs(px[o + 2] - bb) < 12;
  };
  let edge = 0, cover = 0, total = 0;
  for (let x = 0; x < W; x++) { if (!bg(x, 0)) edge++; if (!bg(x, H - 1)) edge++; }
  for (let y = 0; y < H; y++) { if (!bg(0, y)) edge++; if (!bg(W - 1, y)) edge++; }
  for (let y = 0; y < H; y += 4) for (let x = 0; x < W; x += 4) { total++; if (!bg(x, y)) cover++; }
  document.body.dataset.edgePixels = String(edge);
  document.body.dataset.coverage = (cover / total).toFixed(3);
  document.body.dataset.renderer = renderer.capabilities.isWebGL2 ? 'webgl2' : 'webgl1';
  document.body.dataset.depthBits = String(gl.getParameter(gl.DEPTH_BITS));
  document.body.dataset.canvas = W + 'x' + H;
}

let checked = false;
function draw() {
  updateCut();
  renderer.render(scene, camera);
  if (!checked) { selfCheck(); checked = true; }
}
let pending = false;
function later() { if (!pending) { pending = true; requestAnimationFrame(() => { pending = false; draw(); }); } }
controls.addEventListener('change', later);
document.getElementById('cutaway').addEventListener('change', later);
let t0 = null;
function run(now) {
  if (!playBox.checked) { t0 = null; return; }
  if (t0 === null) t0 = now;
  pose((now - t0) / 1000);
  draw();
  requestAnimationFrame(run);
}
if (anim) {
  playBox.addEventListener('change', () => requestAnimationFrame(run));
  // report.html#play starts it running (a link to the running mechanism; the browser tests)
  if (location.hash === '#play') { playBox.checked = true; requestAnimationFrame(run); }
}

// the canvas follows the page width (at most its 900 px design width), keeping its aspect
function resize() {
  const w = Math.max(200, Math.min(900, Math.floor(canvas.parentElement.clientWidth || 900)));
  const h = Math.round(w * 560 / 900);
  renderer.setPixelRatio(1);
  renderer.setSize(w, h, false);
  canvas.style.width = w + 'px'; canvas.style.height = h + 'px';
  camera.aspect = w / h;
  camera.updateProjectionMatrix();
  checked = false;
  draw();
}
window.addEventListener('resize', resize);
resize();
// counts as report.html prints numbers (prs_geom.exports.numbers): digit groups of three
// from 10 000 up, separated by a narrow no-break space
function grouped(n) {
  const s = String(n);
  return s.length < 5 ? s : s.replace(/\B(?=(\d{3})+(?!\d))/g, '\u202f');
}
document.getElementById('viewinfo').textContent =
  grouped(nTri) + ' triangles, display tolerance ' + data.tolerance_mm + ' mm; three.js ' + THREE.REVISION +
  ' (WebGL). Drag to rotate, wheel to zoom, right-drag to pan.';
document.body.dataset.triangles = String(nTri);
document.body.dataset.viewer = 'ok';
