// The TreeSketch page: a drawing pad, the job API (POST /jobs, the events stream,
// DELETE to cancel) and a three.js view of the resulting GLB.  Plain ES modules, no build.
import * as THREE from "three";
import { GLTFLoader } from "three/addons/loaders/GLTFLoader.js";
import { OrbitControls } from "three/addons/controls/OrbitControls.js";

const $ = (id) => document.getElementById(id);
const pad = $("pad");
const ctx = pad.getContext("2d");
// Training sketches have lines about 3-5 px wide at 256 px; the pad is 512 px.
const PEN_WIDTH = 8;
const ERASER_WIDTH = 28;
// A token given as /#token=TOKEN (the fragment never reaches the server) is traded once
// for an HttpOnly, same-site session cookie (POST /session) and taken out of the address
// bar: it never goes into a URL (logs, history, shared links); the cookie goes with every
// request of the page (fetch, the event stream, images, downloads, the 3D view).
const session = (async () => {
  const token = new URLSearchParams(location.hash.slice(1)).get("token");
  if (!token) return;
  history.replaceState(null, "", location.pathname + location.search);
  const r = await fetch("/session", { method: "POST", headers: { Authorization: `Bearer ${token}` } });
  if (!r.ok) say(`The token was refused (${r.status}).`);
})();

// ---- drawing -------------------------------------------------------------------------
let strokes = []; // {erase, width, points: [[x, y], ...]} or {image}
let current = null;
let erasing = false;

function clearPad() {
  ctx.fillStyle = "#fff";
  ctx.fillRect(0, 0, pad.width, pad.height);
}

function drawStroke(s) {
  if (s.image) {
    const { image: im } = s;
    const k = Math.min(pad.width / im.width, pad.height / im.height);
    const w = im.width * k, h = im.height * k;
    ctx.drawImage(im, (pad.width - w) / 2, (pad.height - h) / 2, w, h);
    return;
  }
  ctx.strokeStyle = s.erase ? "#fff" : "#000";
  ctx.fillStyle = ctx.strokeStyle;
  ctx.lineWidth = s.width;
  ctx.lineCap = "round";
  ctx.lineJoin = "round";
  const p = s.points;
  if (p.length === 1) {
    ctx.beginPath();
    ctx.arc(p[0][0], p[0][1], s.width / 2, 0, 2 * Math.PI);
    ctx.fill();
    return;
  }
  ctx.beginPath();
  ctx.moveTo(p[0][0], p[0][1]);
  for (let i = 1; i < p.length; i++) ctx.lineTo(p[i][0], p[i][1]);
  ctx.stroke();
}

function redraw() {
  clearPad();
  strokes.forEach(drawStroke);
}

function padPoint(ev) {
  const r = pad.getBoundingClientRect();
  return [((ev.clientX - r.left) * pad.width) / r.width, ((ev.clientY - r.top) * pad.height) / r.height];
}

pad.addEventListener("pointerdown", (ev) => {
  if (ev.button !== 0 && ev.pointerType === "mouse") return;
  pad.setPointerCapture(ev.pointerId);
  // a pen's eraser end (button 5) erases too
  const erase = erasing || ev.button === 5;
  current = { erase, width: erase ? ERASER_WIDTH : PEN_WIDTH, points: [padPoint(ev)] };
  strokes.push(current);
  drawStroke(current);
  ev.preventDefault();
});
pad.addEventListener("pointermove", (ev) => {
  if (!current) return;
  const events = ev.getCoalescedEvents ? ev.getCoalescedEvents() : [ev];
  for (const e of events.length ? events : [ev]) current.points.push(padPoint(e));
  redraw();
  ev.preventDefault();
});
const endStroke = () => { current = null; };
pad.addEventListener("pointerup", endStroke);
pad.addEventListener("pointercancel", endStroke);

function setTool(erase) {
  erasing = erase;
  $("pen").classList.toggle("active", !erase);
  $("eraser").classList.toggle("active", erase);
  $("pen").setAttribute("aria-pressed", String(!erase));
  $("eraser").setAttribute("aria-pressed", String(erase));
}
$("pen").onclick = () => setTool(false);
$("eraser").onclick = () => setTool(true);
$("undo").onclick = () => { strokes.pop(); redraw(); };
$("clear").onclick = () => { strokes = []; redraw(); };

function loadImageFile(file) {
  if (!file || !file.type.startsWith("image/")) { say("That is not an image."); return; }
  const url = URL.createObjectURL(file);
  const im = new Image();
  im.onload = () => { strokes = [{ image: im }]; redraw(); say("Picture loaded: draw over it or press \"Make the tree\"."); };
  im.onerror = () => say("The browser cannot read that image.");
  im.src = url;
}
$("file").onchange = (ev) => loadImageFile(ev.target.files[0]);
pad.addEventListener("dragover", (ev) => { ev.preventDefault(); pad.classList.add("drop"); });
pad.addEventListener("dragleave", () => pad.classList.remove("drop"));
pad.addEventListener("drop", (ev) => {
  ev.preventDefault();
  pad.classList.remove("drop");
  loadImageFile(ev.dataTransfer.files[0]);
});
clearPad();

// ---- the job -------------------------------------------------------------------------
let jobId = null;
let events = null;

function say(text) { $("status").textContent = text; }
function setState(state) {
  document.body.dataset.state = state;
  const busy = state === "queued" || state === "running" || state === "sending";
  $("submit").disabled = busy;
  $("cancel").disabled = !busy || !jobId;
}

async function submit(ev) {
  ev.preventDefault();
  if (!strokes.length) { say("The page is empty: draw a tree first."); return; }
  const blob = await new Promise((ok) => pad.toBlob(ok, "image/png"));
  const form = new FormData();
  form.append("sketch", blob, "sketch.png");
  form.append("budget", $("budget").value || "20");
  form.append("refine", $("refine").checked ? "true" : "false");
  if ($("height").value) form.append("height", $("height").value);
  if ($("max_faces").value) form.append("max_faces", $("max_faces").value);
  jobId = null;
  setState("sending");
  say("Sending...");
  $("progress").removeAttribute("value");
  let r;
  try {
    await session;
    r = await fetch("/jobs", { method: "POST", body: form });
  } catch (err) {
    setState("failed");
    say(`The server cannot be reached: ${err}`);
    return;
  }
  const body = await r.json().catch(() => ({}));
  if (r.status !== 202) {
    setState("failed");
    $("progress").value = 0;
    say(`Refused (${r.status}): ${body.detail || r.statusText}`);
    return;
  }
  jobId = body.id;
  document.body.dataset.job = jobId;
  setState(body.state);
  show(body);
  follow(jobId);
}
$("options").addEventListener("submit", submit);

function follow(id) {
  if (events) events.close();
  events = new EventSource(`/jobs/${id}/events`);
  const onEvent = (e) => {
    const body = JSON.parse(e.data);
    if (body.id !== jobId) return;
    show(body);
    if (["done", "failed", "cancelled", "expired"].includes(body.state)) events.close();
  };
  for (const kind of ["progress", "done", "failed", "cancelled", "expired"]) events.addEventListener(kind, onEvent);
  events.onerror = () => { if (document.body.dataset.state === "running") say("Connection lost; retrying..."); };
}

function show(job) {
  setState(job.state);
  const p = job.progress || {};
  const bar = $("progress");
  if (job.state === "queued") {
    bar.removeAttribute("value");
    say(job.position ? `Waiting: ${job.position} job(s) ahead.` : "Waiting for a worker...");
  } else if (job.state === "running") {
    const secs = `${(p.elapsed || 0).toFixed(0)} s`;
    if (p.stage === "refine" && p.evaluations > 0 && p.budget) {
      bar.max = p.budget;
      bar.value = Math.min(p.evaluations, p.budget);
      const best = p.best_loss == null ? "" : `, best distance ${p.best_loss.toFixed(3)}`;
      say(`Refining: ${p.evaluations} of ${p.budget} trees${best}, ${secs}`);
    } else if (p.stage === "render") {
      bar.max = 1; bar.value = 1;
      say(`Making the 3D tree and its pictures... ${secs}`);
    } else {
      bar.removeAttribute("value");
      say(`First estimate... ${secs}`);
    }
  } else if (job.state === "done") {
    bar.max = 1; bar.value = 1;
    say(`Done in ${(job.result.timings.job || job.result.timings.total).toFixed(1)} s.`);
    showResult(job);
  } else if (job.state === "cancelled") {
    bar.max = 1; bar.value = 0;
    say("Cancelled.");
  } else {
    bar.max = 1; bar.value = 0;
    say(`Failed: ${job.error || job.state}`);
  }
}

$("cancel").onclick = async () => {
  if (!jobId) return;
  say("Cancelling...");
  await fetch(`/jobs/${jobId}`, { method: "DELETE" });
};

function showResult(job) {
  const r = job.result;
  const links = job.links;
  $("species").textContent = r.species;
  $("confidence").textContent = `${Math.round(r.confidence * 100)}%`;
  $("distance").textContent = `${r.losses.before.toFixed(3)} → ${r.losses.after.toFixed(3)}`;
  $("warning").hidden = !r.warning;
  $("warning").textContent = r.warning || "";
  $("before").src = links["sketch_before.png"];
  $("after").src = links["sketch_after.png"];
  for (const [id, name] of [["dl-glb", "tree.glb"], ["dl-json", "tree.json"], ["dl-preset", "tree_sapling.py"]]) {
    $(id).href = links[name];
    $(id).classList.remove("disabled");
  }
  loadModel(links["tree.glb"]);
}

// ---- the 3D view ---------------------------------------------------------------------
const view = $("view");
let renderer = null, scene = null, camera = null, controls = null, model = null;

function render() { if (renderer) renderer.render(scene, camera); }

function setupView() {
  renderer = new THREE.WebGLRenderer({ antialias: true, preserveDrawingBuffer: true });
  renderer.setPixelRatio(Math.min(window.devicePixelRatio, 2));
  renderer.outputColorSpace = THREE.SRGBColorSpace;
  view.querySelector(".hint")?.remove();
  view.appendChild(renderer.domElement);
  scene = new THREE.Scene();
  scene.background = new THREE.Color(0xe8eef0);
  scene.add(new THREE.HemisphereLight(0xffffff, 0x667755, 1.6));
  const sun = new THREE.DirectionalLight(0xffffff, 1.8);
  sun.position.set(3, 10, 6);
  scene.add(sun);
  camera = new THREE.PerspectiveCamera(40, 1, 0.01, 1000);
  controls = new OrbitControls(camera, renderer.domElement);
  controls.addEventListener("change", render);
  new ResizeObserver(resize).observe(view);
  resize();
}

function resize() {
  const w = view.clientWidth, h = view.clientHeight;
  if (!w || !h) return;
  renderer.setSize(w, h, false);
  camera.aspect = w / h;
  camera.updateProjectionMatrix();
  render();
}

function loadModel(url) {
  if (!renderer) setupView();
  document.body.dataset.model = "loading";
  new GLTFLoader().load(url, (gltf) => {
    if (model) scene.remove(model);
    model = gltf.scene;
    scene.add(model);
    let meshes = 0;
    model.traverse((o) => {
      if (!o.isMesh) return;
      meshes++;
      const m = o.material;
      m.side = THREE.DoubleSide;
      if (m.alphaTest > 0 && m.map) {
        // alpha-masked leaves seen small: mipmaps average their cut-out alpha below the
        // file's cutoff and whole leaves vanish; a lower cutoff (with coverage-blended
        // edges) keeps the crown as full as it is up close
        m.alphaTest = Math.min(m.alphaTest, 0.2);
        m.alphaToCoverage = true;
        m.needsUpdate = true;
      }
    });
    // frame the tree: look at its middle from the front, a little above
    const box = new THREE.Box3().setFromObject(model);
    const size = box.getSize(new THREE.Vector3());
    const centre = box.getCenter(new THREE.Vector3());
    const dist = (Math.max(size.y, size.x, size.z) / 2 / Math.tan((camera.fov * Math.PI) / 360)) * 1.25;
    camera.position.set(centre.x, centre.y + size.y * 0.1, centre.z + dist);
    camera.near = dist / 100; camera.far = dist * 10;
    camera.updateProjectionMatrix();
    controls.target.copy(centre);
    controls.update();
    render();
    document.body.dataset.meshes = String(meshes);
    document.body.dataset.model = "loaded";
  }, undefined, (err) => {
    document.body.dataset.model = "failed";
    say(`The 3D view cannot load the tree: ${err.message || err}`);
  });
}
