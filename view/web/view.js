// The browser side of tangent-view (docs/viewer.md): draws the scene the server describes,
// follows its states, and answers snapshot requests with a PNG of the canvas.
import * as THREE from 'three';
import { OrbitControls } from 'three/addons/controls/OrbitControls.js';

const params = new URLSearchParams(location.search);
const snapshotMode = params.has('snapshot');
const width = () => (snapshotMode ? Number(params.get('w')) : window.innerWidth);
const height = () => (snapshotMode ? Number(params.get('h')) : window.innerHeight);

const renderer = new THREE.WebGLRenderer({ antialias: !snapshotMode, preserveDrawingBuffer: snapshotMode });
// A browser without a GPU draws WebGL on the CPU (SwiftShader, llvmpipe), on the cores the
// haptic server needs: the live view then draws at half resolution with cheaper shading.
// Snapshots keep full quality (they are taken once).
const gl = renderer.getContext();
const info = gl.getExtension('WEBGL_debug_renderer_info');
const glRenderer = info ? String(gl.getParameter(info.UNMASKED_RENDERER_WEBGL)) : '';
const softwareGL = !snapshotMode && /SwiftShader|llvmpipe|softpipe|Software/i.test(glRenderer);
renderer.setPixelRatio(snapshotMode ? 1 : softwareGL ? 0.5 : window.devicePixelRatio);
renderer.setSize(width(), height());
document.body.prepend(renderer.domElement);

const scene3 = new THREE.Scene();
scene3.background = new THREE.Color(0xf4f4f2);
scene3.add(new THREE.HemisphereLight(0xffffff, 0x707070, 1.6));
const sun = new THREE.DirectionalLight(0xffffff, 1.6);
scene3.add(sun);

// Vertical field of view 45 degrees, y up: tests project points with the same camera.
const camera = new THREE.PerspectiveCamera(45, width() / height(), 1e-4, 100);
const controls = new OrbitControls(camera, renderer.domElement);
controls.enabled = !snapshotMode;

const overlay = document.getElementById('overlay');
const status = document.getElementById('status');
const replayBar = document.getElementById('replay');
const slider = document.getElementById('slider');
const playButton = document.getElementById('play');
const timeLabel = document.getElementById('time');

const meshCache = new Map();  // hash -> BufferGeometry + colour, kept across reconnects
let socket = null;
let sceneInfo = null;
let bodies = [];              // THREE.Group per body
let pending = new Set();      // mesh hashes asked for and not yet received
let state = null;
let size = 1;                 // scene size, metres (marker and arrow scale)
let dirty = true;
let cameraSet = false;
let snapshotWanted = null;    // utime the server asked a snapshot of
const contactMarkers = [];
const normalArrows = [];
const grasp = new THREE.Mesh(new THREE.SphereGeometry(1, 16, 12), new THREE.MeshBasicMaterial({ color: 0x202020 }));
const tool = new THREE.AxesHelper(1);
const forceArrow = new THREE.ArrowHelper(new THREE.Vector3(1, 0, 0), new THREE.Vector3(), 1, 0xd62728);
scene3.add(grasp, tool, forceArrow);
grasp.visible = tool.visible = forceArrow.visible = false;

function send(message) {
  if (socket && socket.readyState === WebSocket.OPEN) socket.send(JSON.stringify(message));
}

function connect() {
  socket = new WebSocket(`ws://${location.host}/`);
  socket.onopen = () => { status.textContent = 'connected'; };
  socket.onclose = () => {
    status.textContent = 'disconnected: retrying';
    setTimeout(connect, 1000);
  };
  socket.onmessage = (event) => {
    const m = JSON.parse(event.data);
    if (m.type === 'scene') onScene(m);
    else if (m.type === 'mesh') onMesh(m);
    else if (m.type === 'state') onState(m);
    else if (m.type === 'snapshot') { snapshotWanted = m.utime; dirty = true; }
    else if (m.type === 'error') console.warn('tangent-view:', m.message);
  };
}

function onScene(m) {
  sceneInfo = m;
  for (const g of bodies) scene3.remove(g);
  bodies = m.bodies.map(() => new THREE.Group());
  for (const g of bodies) {
    // The body frame: x red, y green, z blue at the body's origin (scaled to the scene in fitScene).
    const frame = new THREE.AxesHelper(1);
    frame.name = 'frame';
    g.add(frame);
    scene3.add(g);
  }
  pending = new Set();
  for (const entry of m.meshes) {
    if (meshCache.has(entry.hash)) addMesh(entry.hash, entry.body);
    else if (!pending.has(entry.hash)) { pending.add(entry.hash); send({ type: 'need', hash: entry.hash }); }
  }
  const saved = localStorage.getItem('tangent-view-camera:' + m.name);
  const cam = m.camera || (saved ? JSON.parse(saved) : null);
  if (cam) setCamera(cam.position, cam.target);
  replayBar.style.display = m.mode === 'replay' ? 'flex' : 'none';
  if (m.mode === 'replay') slider.max = m.duration;
  dirty = true;
}

function onMesh(m) {
  const g = new THREE.BufferGeometry();
  g.setAttribute('position', new THREE.Float32BufferAttribute(m.positions, 3));
  g.setAttribute('normal', new THREE.Float32BufferAttribute(m.normals, 3));
  g.setIndex(m.indices);
  g.computeBoundingSphere();
  meshCache.set(m.hash, { geometry: g, colour: m.colour });
  pending.delete(m.hash);
  addMesh(m.hash, m.body);
  // The last mesh in: place and fit to the state already received (a paused replay sends none
  // until something changes).
  if (pending.size === 0 && state) onState(state);
  dirty = true;
}

function addMesh(hash, body) {
  const { geometry, colour } = meshCache.get(hash);
  const color = new THREE.Color(colour[0], colour[1], colour[2]);
  const material = softwareGL
    ? new THREE.MeshLambertMaterial({ color, side: THREE.DoubleSide })
    : new THREE.MeshStandardMaterial({ color, roughness: 0.55, metalness: 0.05, side: THREE.DoubleSide });
  bodies[body].add(new THREE.Mesh(geometry, material));
}

function setCamera(position, target) {
  camera.position.fromArray(position);
  controls.target.fromArray(target);
  camera.lookAt(controls.target);
  controls.update();
  cameraSet = true;
}

// Size of the scene from its meshes at the current poses; the camera looks at it from the
// front-right-above unless the server or a saved view says otherwise.
let fitted = false;
function fitScene() {
  const box = new THREE.Box3();
  for (const g of bodies) for (const c of g.children) if (c.isMesh) box.expandByObject(c);
  if (box.isEmpty()) return;
  fitted = true;
  const centre = box.getCenter(new THREE.Vector3());
  size = box.getSize(new THREE.Vector3()).length();
  camera.near = size * 1e-3;
  camera.far = size * 100;
  camera.updateProjectionMatrix();
  if (!cameraSet) {
    // The bounding sphere fits the narrower of the two fields of view.
    const half = THREE.MathUtils.degToRad(camera.fov / 2);
    const narrow = Math.min(half, Math.atan(Math.tan(half) * camera.aspect));
    const dir = new THREE.Vector3(0.55, 0.35, 1).normalize();
    setCamera(centre.clone().addScaledVector(dir, 0.6 * size / Math.sin(narrow)).toArray(), centre.toArray());
  }
  grasp.scale.setScalar(size * 0.006);
  for (const g of bodies) g.getObjectByName('frame').scale.setScalar(size * 0.04);
  tool.scale.setScalar(size * 0.06);
}

function marker(list, i, make) {
  while (list.length <= i) { const o = make(); list.push(o); scene3.add(o); }
  list[i].visible = true;
  return list[i];
}

function onState(m) {
  state = m;
  m.poses.forEach((x, b) => {
    if (!bodies[b]) return;
    bodies[b].position.set(x[0], x[1], x[2]);
    bodies[b].quaternion.set(x[4], x[5], x[6], x[3]);  // three.js: (x, y, z, w)
  });
  // The first view is fitted to the bodies where the server has them, once all meshes are in.
  if (!fitted && sceneInfo && pending.size === 0) fitScene();
  const r = size * 0.008;
  m.contacts.forEach((c, i) => {
    // Contact points in unlit magenta so they read against any shading (and tests find them).
    const s = marker(contactMarkers, i, () => new THREE.Mesh(
      new THREE.SphereGeometry(1, 16, 12), new THREE.MeshBasicMaterial({ color: 0xff00ff, depthTest: false })));
    s.renderOrder = 10;
    s.scale.setScalar(r);
    s.position.fromArray(c.pa);
    const a = marker(normalArrows, i, () => new THREE.ArrowHelper(new THREE.Vector3(0, 0, 1), new THREE.Vector3(), 1, 0x9b00b0));
    a.position.fromArray(c.pa);
    a.setDirection(new THREE.Vector3().fromArray(c.n));
    a.setLength(size * 0.05, size * 0.012, size * 0.006);
  });
  for (let i = m.contacts.length; i < contactMarkers.length; ++i) contactMarkers[i].visible = normalArrows[i].visible = false;
  grasp.visible = true;
  grasp.position.fromArray(m.grasp);
  tool.visible = !!m.tool;
  tool.position.fromArray(m.grasp);
  if (m.tool) tool.quaternion.set(m.tool[1], m.tool[2], m.tool[3], m.tool[0]);
  const f = m.force ? new THREE.Vector3().fromArray(m.force) : new THREE.Vector3();
  const fn = f.length();
  forceArrow.visible = fn > 1e-6;
  if (forceArrow.visible) {
    forceArrow.position.fromArray(m.grasp);
    forceArrow.setDirection(f.clone().divideScalar(fn));
    const len = size * 0.3 * Math.min(1, fn / (sceneInfo ? sceneInfo.max_force : 1)) + size * 0.02;
    forceArrow.setLength(len, size * 0.02, size * 0.01);
  }
  const lines = [`${sceneInfo ? sceneInfo.name : ''}  (${sceneInfo ? sceneInfo.mode : ''}${softwareGL ? ', software WebGL: half resolution' : ''})`];
  if (m.stats) {
    lines.push(`loop ${m.stats.rate_hz.toFixed(0)} Hz   tick p50 ${m.stats.p50_us.toFixed(1)} µs  p99 ${m.stats.p99_us.toFixed(1)} µs`);
    lines.push(`violation ${m.stats.violation.toExponential(1)} m`);
  }
  lines.push(`contacts ${m.contacts.length}   force ${fn.toFixed(2)} N`);
  for (const c of m.contacts.slice(0, 4)) lines.push(`  d = ${(c.d * 1e6).toFixed(3)} µm   λ = ${c.f.toFixed(3)} N`);
  overlay.textContent = lines.join('\n');
  if (m.replay) {
    slider.value = m.replay.t;
    timeLabel.textContent = `${m.replay.t.toFixed(2)} / ${m.replay.duration.toFixed(2)} s`;
    playButton.textContent = m.replay.playing ? 'pause' : 'play';
  }
  dirty = true;
}

// Camera kept across reconnects and reloads: in this browser, and by the server for new pages.
let cameraTimer = null;
controls.addEventListener('change', () => {
  dirty = true;
  if (snapshotMode || !sceneInfo) return;
  clearTimeout(cameraTimer);
  cameraTimer = setTimeout(() => {
    const view = { position: camera.position.toArray(), target: controls.target.toArray() };
    localStorage.setItem('tangent-view-camera:' + sceneInfo.name, JSON.stringify(view));
    send({ type: 'camera', ...view });
  }, 200);
});

playButton.onclick = () => send({ type: playButton.textContent === 'play' ? 'play' : 'pause' });
slider.oninput = () => send({ type: 'seek', t: Number(slider.value) });
window.addEventListener('resize', () => {
  if (snapshotMode) return;
  renderer.setSize(width(), height());
  camera.aspect = width() / height();
  camera.updateProjectionMatrix();
  dirty = true;
});

// Rendering follows the display: at most one frame per animation frame, none when nothing moved.
function frame() {
  requestAnimationFrame(frame);
  if (!dirty) return;
  dirty = false;
  sun.position.copy(camera.position);
  renderer.render(scene3, camera);
  if (snapshotWanted !== null && state && fitted && pending.size === 0 && state.utime >= snapshotWanted) {
    send({ type: 'png', utime: state.utime, data: snapshotPng() });
    snapshotWanted = null;
  }
}

// The canvas with the overlay's text drawn in its corner, as the page shows it.
function snapshotPng() {
  const c = document.createElement('canvas');
  c.width = renderer.domElement.width;
  c.height = renderer.domElement.height;
  const g = c.getContext('2d');
  g.drawImage(renderer.domElement, 0, 0);
  const lines = overlay.textContent.split('\n');
  g.font = '13px sans-serif';
  const w = Math.max(...lines.map((l) => g.measureText(l).width)) + 18;
  g.fillStyle = 'rgba(255, 255, 255, 0.82)';
  g.fillRect(8, 8, w, lines.length * 17 + 10);
  g.fillStyle = '#222';
  lines.forEach((l, i) => g.fillText(l, 17, 26 + i * 17));
  return c.toDataURL('image/png');
}

connect();
frame();
