// The TreeSketch page: a drawing pad, the job API (POST /jobs, the events stream,
// DELETE to cancel) and a three.js view of the resulting GLB.  Plain ES modules, no build.
// "Draw from this side": the finished tree turned in the 3D view, its outline from there
// (GET /jobs/{id}/outline.png) shown faintly behind the pad, and the next job sent with
// every drawing of the tree, each with its turn from the first (the form's "yaw").
import * as THREE from "three";
import { GLTFLoader } from "three/addons/loaders/GLTFLoader.js";
import { OrbitControls } from "three/addons/controls/OrbitControls.js";

const $ = (id) => document.getElementById(id);
const pad = $("pad");
const ctx = pad.getContext("2d");
// Training sketches have lines about 3-5 px wide at 256 px; the pad is 512 px: the
// brush starts at 8 px (its slider: 2 to 40); the eraser is 3.5 times as wide.
let penWidth = 8;
const eraserWidth = () => Math.max(12, Math.round(penWidth * 3.5));
// A token given as /#token=TOKEN (the fragment never reaches the server) is traded once
// for an HttpOnly, same-site session cookie (POST /session) and taken out of the address
// bar: it never goes into a URL (logs, history, shared links); the cookie goes with every
// request of the page (fetch, the event stream, images, downloads, the 3D view).
// Every API call waits for it (api()).
const session = (async () => {
  const token = new URLSearchParams(location.hash.slice(1)).get("token");
  if (!token) return;
  history.replaceState(null, "", location.pathname + location.search);
  const r = await fetch("/session", { method: "POST", headers: { Authorization: `Bearer ${token}` } });
  if (!r.ok) say(`The token was refused (${r.status}).`);
})();
const api = async (url, options) => { await session; return fetch(url, options); };

// ---- drawing -------------------------------------------------------------------------
let strokes = []; // {erase, width, points: [[x, y], ...]}, {image} or {clear}
let undone = []; // what Undo took, for Redo
let current = null;
let erasing = false;
// one history for the pad and the tree: Ctrl+Z undoes what was changed last, the Undo
// buttons their own (the pad's, the tree's); "pad" | "tree", oldest first
let steps = [];
let redoSteps = [];
function noteStep(kind) {
  steps.push(kind);
  redoSteps = redoSteps.filter((k) => k !== kind);
}
function dropLast(list, kind) {
  const i = list.lastIndexOf(kind);
  if (i >= 0) list.splice(i, 1);
}
// the page is empty when nothing was drawn since the last Clear
const drawn = () => strokes.length > 0 && !strokes[strokes.length - 1].clear;

function clearPad() {
  ctx.fillStyle = "#fff";
  ctx.fillRect(0, 0, pad.width, pad.height);
}

function drawStroke(s) {
  if (s.clear) { clearPad(); return; }
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
  current = { erase, width: erase ? eraserWidth() : penWidth, points: [padPoint(ev)] };
  addStroke(current);
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
const endStroke = () => { if (current) { current = null; savePad(); } };
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
function addStroke(s) { strokes.push(s); undone = []; noteStep("pad"); }
function undo() {
  if (!strokes.length) return;
  undone.push(strokes.pop());
  dropLast(steps, "pad");
  redoSteps.push("pad");
  redraw();
  savePad();
}
function redo() {
  if (!undone.length) return;
  strokes.push(undone.pop());
  dropLast(redoSteps, "pad");
  steps.push("pad");
  redraw();
  savePad();
}
$("undo").onclick = undo;
$("redo").onclick = redo;
// Clear is a step of its own, so Undo brings the drawing back
$("clear").onclick = () => { if (drawn()) { addStroke({ clear: true }); redraw(); savePad(); } };
// Ctrl+Z: the latest change, of the pad or of the tree (a step whose pad or tree has
// gone meanwhile, e.g. another job's, is skipped)
function undoLatest() {
  while (steps.length) {
    const kind = steps[steps.length - 1];
    if (kind === "pad" && strokes.length) { undo(); return; }
    if (kind === "tree" && treeSteps.length) { undoTree(); return; }
    steps.pop();
  }
}
function redoLatest() {
  while (redoSteps.length) {
    const kind = redoSteps[redoSteps.length - 1];
    if (kind === "pad" && undone.length) { redo(); return; }
    if (kind === "tree" && treeRedo.length) { redoTree(); return; }
    redoSteps.pop();
  }
}
// fields where Ctrl+Z is the browser's own (typing); sliders, boxes and lists are not
const TYPED = new Set(["text", "number", "search", "email", "url", "password", "tel"]);
document.addEventListener("keydown", (ev) => {
  if (!(ev.ctrlKey || ev.metaKey) || ev.altKey) return;
  const t = ev.target;
  if (t && ((t.tagName === "INPUT" && TYPED.has(t.type)) || t.tagName === "TEXTAREA" || t.isContentEditable)) return;
  const key = ev.key.toLowerCase();
  if (key === "z" && !ev.shiftKey) { undoLatest(); ev.preventDefault(); }
  else if ((key === "z" && ev.shiftKey) || key === "y") { redoLatest(); ev.preventDefault(); }
});
$("brush").oninput = () => { penWidth = Number($("brush").value); $("brush-size").textContent = String(penWidth); };
$("upload").onclick = () => $("file").click();

function loadImageFile(file) {
  if (!file || !file.type.startsWith("image/")) { say("That is not an image."); return; }
  const url = URL.createObjectURL(file);
  const im = new Image();
  im.onload = () => { addStroke({ clear: true }); addStroke({ image: im }); redraw(); savePad(); say("Picture loaded: draw over it or press \"Make the tree\"."); };
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

// the pad is kept for the tab (sessionStorage): a reload brings it back ("" once cleared)
const PAD_KEY = "treesketch.pad";
let padTimer = null;
function savePad() {
  if (side) return; // a drawing from another side is not the tab's drawing
  clearTimeout(padTimer);
  padTimer = setTimeout(() => {
    try { sessionStorage.setItem(PAD_KEY, drawn() ? pad.toDataURL("image/png") : ""); } catch { /* full or off */ }
  }, 150);
}
// the pad shows ``url``'s picture as its only content (no undo steps); a promise
function padFrom(url) {
  return new Promise((ok) => {
    const im = new Image();
    im.onload = () => { strokes = [{ image: im }]; undone = []; redraw(); document.body.dataset.pad = "restored"; ok(true); };
    im.onerror = () => ok(false);
    im.src = url;
  });
}
function keptPad() {
  try { return sessionStorage.getItem(PAD_KEY); } catch { return null; }
}

// ---- the job -------------------------------------------------------------------------
let jobId = null;
let events = null;
let shownPreview = 0; // the version of the job's current best tree on show
let defaultBudget = null; // the server's one default budget (GET /controls)
const MINE = "treesketch.jobs"; // this browser's job ids, newest first
const phone = () => window.matchMedia("(max-width: 700px)").matches;

function say(text) { $("status").textContent = text; }
function setState(state) {
  document.body.dataset.state = state;
  const busy = state === "queued" || state === "running" || state === "sending";
  $("submit").disabled = busy;
  $("cancel").disabled = !busy || !jobId;
}

let sending = false; // a job is being sent: a second press (a double click) is ignored
async function submit(ev) {
  ev.preventDefault();
  if (sending || $("submit").disabled) return;
  if (!drawn()) { say(side ? "Draw the tree from this side first." : "The page is empty: draw a tree first."); return; }
  sending = true;
  try { await send(); } finally { sending = false; }
}
async function send() {
  jobId = null;
  setState("sending");
  const blob = await new Promise((ok) => pad.toBlob(ok, "image/png"));
  // drawing from another side: the tree's earlier drawings go too, the first at yaw 0
  const views = side ? [...side.views, { blob, yaw: side.turn }] : [{ blob, yaw: 0 }];
  const form = new FormData();
  views.forEach((v, i) => form.append("sketch", v.blob, i === 0 ? "sketch.png" : `view${i + 1}.png`));
  if (views.length > 1) for (const v of views) form.append("yaw", String(v.yaw));
  if ($("budget").value) form.append("budget", $("budget").value);
  form.append("refine", $("refine").checked ? "true" : "false");
  if ($("height").value) form.append("height", $("height").value);
  if ($("max_faces").value) form.append("max_faces", $("max_faces").value);
  if ($("species-pick").value) form.append("species", $("species-pick").value);
  say("Sending...");
  $("progress").removeAttribute("value");
  let r;
  try {
    r = await api("/jobs", { method: "POST", body: form });
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
  sentViews.set(body.id, views);
  keepViews(body.id, views);
  if (side) leaveSide(false);
  startJob(body);
  remember(body.id);
}
$("options").addEventListener("submit", submit);

// a job on show: its id in the address (reload and share bring it back)
function startJob(body) {
  jobId = body.id;
  shownPreview = 0;
  framedJob = null;
  endEdit();
  clearResult();
  document.body.dataset.job = jobId;
  const url = new URL(location.href);
  url.search = "";
  url.searchParams.set("job", jobId);
  history.replaceState(null, "", url);
  showLink();
  setState(body.state);
  show(body);
  if (!["done", "failed", "cancelled", "expired"].includes(body.state)) follow(jobId);
}

function follow(id) {
  if (events) events.close();
  events = new EventSource(`/jobs/${id}/events`);
  const onEvent = (e) => {
    const body = JSON.parse(e.data);
    if (body.id !== jobId) return;
    show(body);
    if (["done", "failed", "cancelled", "expired"].includes(body.state)) { events.close(); refreshRecent(); }
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
    const tree = p.preview ? " (the best tree so far is shown)" : "";
    if (p.stage === "refine" && p.evaluations > 0 && p.budget) {
      const n = Math.min(p.evaluations, p.budget); // never past the plan
      bar.max = p.budget;
      bar.value = n;
      // the search's quick sketches: the result's distance is measured again, in full
      const best = p.best_loss == null ? "" : `, best quick-sketch distance ${p.best_loss.toFixed(3)}`;
      say(`Refining: ${n} of ${p.budget} trees${best}, ${secs}${tree}`);
    } else if (p.stage === "render") {
      bar.max = 1; bar.value = 1;
      say(`Making the 3D tree and its pictures... ${secs}`);
    } else {
      bar.removeAttribute("value");
      say(`First estimate... ${secs}`);
    }
    if (p.preview && p.preview > shownPreview) showPreview(job, p.preview);
  } else if (job.state === "done") {
    bar.max = 1; bar.value = 1;
    say(`Done in ${(job.result.timings.job || job.result.timings.total).toFixed(1)} s.`);
    showResult(job);
  } else if (job.state === "cancelled") {
    bar.max = 1; bar.value = 0;
    say("Cancelled.");
    $("view-note").textContent = shownPreview ? "cancelled: its best tree so far (no files)" : "";
  } else {
    bar.max = 1; bar.value = 0;
    say(`Failed: ${job.error || job.state}`);
    $("view-note").textContent = shownPreview ? "failed: its best tree so far (no files)" : "";
  }
}

// the job's current best tree while the refinement runs (the first estimate at once)
function showPreview(job, version) {
  shownPreview = version;
  document.body.dataset.preview = String(version);
  $("before").src = `${job.links["preview/sketch.png"]}?v=${version}`;
  loadModel(`${job.links["preview/tree.glb"]}?v=${version}`, frameFor(job));
  framedJob = job.id;
  $("view-note").textContent = "best so far; refining...";
  if (version === 1 && phone()) $("result-panel").scrollIntoView({ behavior: "smooth" });
}

$("cancel").onclick = async () => {
  if (!jobId) return;
  say("Cancelling...");
  await api(`/jobs/${jobId}`, { method: "DELETE" });
};

// one job on screen: a new job (or one from the address) takes the last one's result off
const DOWNLOADS = [["dl-glb", "tree.glb"], ["dl-glb-light", "tree_view.glb"], ["dl-obj", null], ["dl-json", "tree.json"], ["dl-preset", "tree_sapling.py"]];
function clearResult() {
  for (const [id] of DOWNLOADS) {
    $(id).removeAttribute("href");
    $(id).classList.add("disabled");
  }
  $("glb-note").textContent = "";
  for (const id of ["species", "confidence", "distance"]) $(id).textContent = "-";
  $("species-label").textContent = "Species";
  $("species-text").textContent = "";
  $("warning").hidden = true;
  $("warning").textContent = "";
  $("before").removeAttribute("src");
  $("after").removeAttribute("src");
  clearOutlines();
  $("view-note").textContent = "";
  delete document.body.dataset.preview;
  delete document.body.dataset.shown;
}

function showResult(job) {
  const r = job.result;
  const links = job.links;
  shownJob = job;
  // a drawing that may be no tree: the question leads (showCandidates), the numbers follow
  const details = (r.warning || "").replace(/;? *is this a sketch of a tree\?$/, "");
  $("warning").hidden = !r.warning;
  $("warning").textContent = r.warning ? `Why: ${details}.` : "";
  $("before").src = links["sketch_before.png"];
  $("after").src = links["sketch_after.png"];
  for (const [id, name] of DOWNLOADS) {
    $(id).href = name ? links[name] : "#obj";
    $(id).classList.remove("disabled");
  }
  describeGlb(job);
  showCandidates(job);
  showFacts(null);
  showViews(job);
  showOutlines(job);
  updateSideButton();
  $("view-note").textContent = "";
  if (phone() && !restoring) $("result-panel").scrollIntoView({ behavior: "smooth" });
  // a candidate species from the address (a reload, a link): its tree, not the job's
  const cand = pending && pending.job === job.id ? pending.cand : 0;
  framedJob = job.id;
  if (cand > 0 && cand < Math.min(3, (r.candidates || []).length)) { switchTo(cand); return; }
  // the viewer's light tree; the GLB download keeps full detail
  loadModel(links["tree_view.glb"], frameFor(job));
  startEdit(r);
}

// the full GLB's size and triangles (its header, read with a range request), beside the
// button; the light one is the 3D view's
async function describeGlb(job) {
  const url = job.links["tree.glb"];
  const note = (text) => { if (shownJob === job) $("glb-note").textContent = text; };
  const light = table ? `; light: at most ${Math.round(table.view_faces / 1000)}k` : "";
  try {
    const head = await api(url, { headers: { Range: "bytes=0-19" } });
    if (head.status !== 206) { note(""); return; }
    const b = new DataView(await head.arrayBuffer());
    const bytes = b.getUint32(8, true), jsonLength = b.getUint32(12, true);
    const r = await api(url, { headers: { Range: `bytes=20-${19 + jsonLength}` } });
    const gltf = JSON.parse(new TextDecoder().decode(await r.arrayBuffer()));
    let triangles = 0;
    for (const m of gltf.meshes || []) for (const p of m.primitives) {
      const acc = gltf.accessors[p.indices ?? p.attributes.POSITION];
      triangles += Math.round(acc.count / 3);
    }
    const mb = bytes / 1e6;
    note(`full detail: ${mb.toFixed(mb < 10 ? 1 : 0)} MB, ${Math.round(triangles / 1000)}k triangles${light}`);
  } catch { note(""); }
}

// ---- the species: the picker (GET /species) and the result's candidates ---------------
let speciesNames = new Map(); // name -> what people call it
let shownJob = null; // the finished job on show
let switchCount = 0; // the switches to a candidate so far (a late answer of an earlier one is dropped)

async function loadSpecies() {
  const r = await api("/species").catch(() => null);
  if (!r || !r.ok) return;
  const { species } = await r.json();
  speciesNames = new Map(species.map((s) => [s.name, s.display]));
  const pick = $("species-pick");
  const byName = [...species].sort((a, b) => a.display.localeCompare(b.display));
  for (const s of byName) pick.append(new Option(s.display, s.name));
  document.body.dataset.species = "ready";
}
const displayName = (name) => speciesNames.get(name) || name;
// a species that kept a sliver of the probability is not ruled out: "<1%", not "0%"
const percent = (p) => (p > 0 && p < 0.005 ? "<1%" : `${Math.round(p * 100)}%`);

// the result's species in words and its candidates as thumbnails to switch to
function showCandidates(job) {
  const r = job.result;
  const box = $("candidates");
  box.replaceChildren();
  const cands = (r.candidates || []).slice(0, 3);
  // a species picked by hand was not judged from the drawing; a drawing that may be no
  // tree leads with the question, the species after it
  const picked = (job.options || {}).species;
  let text = r.species_text ? `It is ${r.species_text}.` : "";
  if (picked) text = `You picked this species: ${displayName(picked)}. It was not judged from the drawing.`;
  else if (r.warning) text = `Is this a tree? The drawing does not look much like one.${r.species_text ? ` If it is, the closest is ${r.species_text}.` : ""}`;
  $("species-text").textContent = text;
  cands.forEach((c, i) => {
    const b = document.createElement("button");
    b.type = "button";
    b.className = "candidate";
    b.dataset.species = c.species;
    b.setAttribute("aria-pressed", String(i === 0));
    b.title = i === 0 ? `The tree the drawing gave: ${c.name}` : `Show it as ${c.name} instead`;
    const im = document.createElement("img");
    im.src = job.links[`candidate${i + 1}.png`];
    im.alt = "";
    const name = document.createElement("span");
    name.className = "cand-name";
    name.textContent = c.name;
    const prob = document.createElement("span");
    prob.className = "cand-prob";
    const p = picked && c.species === picked ? "your pick" : percent(c.probability);
    prob.textContent = p;
    b.setAttribute("aria-label", `${c.name}, ${p}`);
    b.append(im, name, prob);
    b.onclick = () => switchTo(i);
    box.append(b);
  });
  $("candidates-panel").hidden = !cands.length && !r.species_text;
}

// the facts of the tree on show: the job's own (null) or candidate ``c``
function showFacts(c) {
  const r = shownJob.result;
  const species = c ? c.species : r.species;
  $("species").textContent = displayName(species);
  document.body.dataset.shown = species;
  const picked = (shownJob.options || {}).species;
  $("species-label").textContent = r.warning && !picked ? "Closest species" : "Species";
  $("confidence").textContent = picked && species === picked ? "picked by you" : percent(c ? c.probability : r.confidence);
  if (!c) $("distance").textContent = `${r.losses.before.toFixed(3)} → ${r.losses.after.toFixed(3)}`;
  else $("distance").textContent = c.distance == null ? "– (not refined)" : c.distance.toFixed(3);
}

// show candidate ``i`` (0: the job's own tree) in the 3D view; the controls edit it and
// the downloads are of it
async function switchTo(i) {
  if (!shownJob) return;
  const job = shownJob;
  const cands = job.result.candidates || [];
  const c = cands[i];
  if (!c) return;
  const mine = ++switchCount;
  for (const [k, b] of [...$("candidates").children].entries()) b.setAttribute("aria-pressed", String(k === i));
  showFacts(i === 0 ? null : c);
  $("view-note").textContent = "";
  if (i === 0) {
    // the job's own tree and files again
    loadModel(job.links["tree_view.glb"], true);
    setPreset(true);
    startEdit(job.result);
    updateUrl();
    return;
  }
  setPreset(false);
  updateSideButton();
  $("edit-status").textContent = `Growing the ${c.name}...`;
  await startEdit({ params: c.params, species: c.species, yaw: job.result.yaw }, true, i);
  if (mine !== switchCount || !edit) return;
  const r = await treeRequest({}, "model/gltf-binary", table ? table.view_faces : null);
  if (mine !== switchCount) return;
  if (!r.ok) { $("edit-status").textContent = `Refused (${r.status})`; return; }
  loadModel(await r.arrayBuffer(), true);
  $("edit-status").textContent = "";
  updateUrl();
}

// the Sapling preset is the job's own tree's: a switched or edited tree has none
function setPreset(own) {
  $("dl-preset").classList.toggle("disabled", !own);
  $("dl-preset").title = own ? "" : "The Sapling preset is of the drawing's own tree: download the JSON (Sapling's keys) instead";
}

// ---- examples, recent jobs, a job from the address -----------------------------------
async function loadGallery() {
  const r = await api("/examples").catch(() => null);
  if (!r || !r.ok) { $("examples").hidden = true; return; }
  const { examples } = await r.json();
  const box = $("gallery");
  for (const ex of examples) {
    const b = document.createElement("button");
    b.type = "button";
    b.className = "example";
    b.setAttribute("role", "listitem");
    b.title = `Start from the example drawing "${ex.name}"`;
    const im = document.createElement("img");
    im.src = ex.url;
    im.alt = ex.name;
    b.append(im, document.createTextNode(ex.name));
    b.tabIndex = box.children.length ? -1 : 0; // one tab stop: the arrows move along
    b.onclick = () => {
      const pic = new Image();
      pic.onload = () => { addStroke({ clear: true }); addStroke({ image: pic }); redraw(); savePad(); say(`Example "${ex.name}" loaded: press "Make the tree".`); };
      pic.src = ex.url;
    };
    box.append(b);
  }
}
$("gallery").addEventListener("keydown", (ev) => {
  const moves = { ArrowRight: 1, ArrowDown: 1, ArrowLeft: -1, ArrowUp: -1 };
  if (!(ev.key in moves) && ev.key !== "Home" && ev.key !== "End") return;
  const items = [...$("gallery").children];
  const i = items.indexOf(document.activeElement);
  if (i < 0) return;
  let j = ev.key === "Home" ? 0 : ev.key === "End" ? items.length - 1 : i + moves[ev.key];
  j = Math.max(0, Math.min(items.length - 1, j));
  items[i].tabIndex = -1;
  items[j].tabIndex = 0;
  items[j].focus();
  ev.preventDefault();
});

function mine() {
  try { return JSON.parse(localStorage.getItem(MINE) || "[]"); } catch { return []; }
}
function remember(id) {
  const ids = [id, ...mine().filter((x) => x !== id)].slice(0, 20);
  localStorage.setItem(MINE, JSON.stringify(ids));
  refreshRecent();
}

async function refreshRecent() {
  const ids = mine();
  const list = $("recent");
  if (!ids.length) return;
  const r = await api("/jobs?limit=200").catch(() => null);
  if (!r || !r.ok) return;
  const byId = new Map((await r.json()).jobs.map((j) => [j.id, j]));
  list.replaceChildren();
  for (const id of ids) {
    const j = byId.get(id);
    if (!j) continue;
    const li = document.createElement("li");
    const a = document.createElement("a");
    a.href = `?job=${id}`;
    const drawings = j.options && j.options.yaws ? ` (${j.options.yaws.length + 1} drawings)` : "";
    const what = (j.state === "done" ? j.result.species : j.state) + drawings;
    a.textContent = `${new Date(j.created * 1000).toLocaleString()}: ${what}`;
    if (id === jobId) a.setAttribute("aria-current", "true");
    li.append(a);
    list.append(li);
  }
}

// the settings of the next job, kept for the tab (a reload keeps them)
const SETTINGS_KEY = "treesketch.settings";
const SETTINGS = ["species-pick", "budget", "height", "max_faces", "refine"];
function saveSettings() {
  const kept = {};
  for (const id of SETTINGS) kept[id] = id === "refine" ? $(id).checked : $(id).value;
  try { sessionStorage.setItem(SETTINGS_KEY, JSON.stringify(kept)); } catch { /* full or off */ }
}
function setSettings(kept) {
  for (const id of SETTINGS) {
    if (!(id in kept)) continue;
    if (id === "refine") $(id).checked = Boolean(kept[id]);
    else $(id).value = kept[id] == null ? "" : String(kept[id]);
  }
}
$("options").addEventListener("input", saveSettings);
$("options").addEventListener("change", saveSettings);

// the edits of the tree on show, in the address (a reload and a shared link bring them
// back): ?job=ID&cand=I&e.NAME=VALUE...
let pending = null; // {job, cand, controls}: edits from the address, put on once it loads
let restoring = false;
function updateUrl() {
  if (!jobId) return;
  const url = new URL(location.href);
  url.search = "";
  url.searchParams.set("job", jobId);
  if (edit && edit.initial && shownJob && shownJob.id === jobId) {
    if (edit.cand) url.searchParams.set("cand", String(edit.cand));
    for (const [k, v] of Object.entries(changedControls())) url.searchParams.set(`e.${k}`, String(v));
  }
  history.replaceState(null, "", url);
  showLink();
}
function showLink() {
  $("share-link").value = location.href;
  $("share").hidden = !jobId;
}
$("copy-link").onclick = async () => {
  const link = location.href;
  let ok = true;
  try { await navigator.clipboard.writeText(link); } catch {
    $("share-link").select();
    ok = document.execCommand && document.execCommand("copy");
  }
  document.body.dataset.copied = ok ? "yes" : "";
  $("share-note").textContent = ok ? "Copied." : "Select the link and copy it.";
};

async function restoreFromUrl() {
  const query = new URLSearchParams(location.search);
  const id = query.get("job");
  let kept = null;
  try { kept = JSON.parse(sessionStorage.getItem(SETTINGS_KEY) || "null"); } catch { /* none */ }
  if (kept) setSettings(kept);
  const pad = keptPad();
  if (pad) await padFrom(pad);
  if (!id) return;
  const r = await api(`/jobs/${encodeURIComponent(id)}`).catch(() => null);
  if (!r || !r.ok) { say(`Job ${id} is not on this server.`); return; }
  const job = await r.json();
  const controls = {};
  for (const [k, v] of query) if (k.startsWith("e.")) controls[k.slice(2)] = v;
  pending = { job: job.id, cand: Number(query.get("cand")) || 0, controls };
  // a shared link: the settings the tree was made with, and its drawing
  if (!kept) {
    const o = job.options || {};
    setSettings({ "species-pick": o.species || "", budget: o.budget, height: o.height, max_faces: o.max_faces, refine: o.refine !== false });
  }
  if (pad === null) padFrom(`/jobs/${encodeURIComponent(job.id)}/drawing.png`).then((ok) => { if (ok) savePad(); });
  restoreViews(id);
  fetchViews(job);
  restoring = true;
  startJob(job);
  restoring = false;
}

// ---- shaping the tree: the controls (GET /controls, POST /trees) ---------------------
let table = null; // GET /controls
let edit = null; // {params, species, yaw, initial: {name: value}, busy, again, edited, switched}
let editTimer = null;

async function loadControls() {
  const r = await api("/controls").catch(() => null);
  if (!r || !r.ok) return;
  table = await r.json();
  defaultBudget = table.default_budget;
  if (!$("budget").value) $("budget").value = String(defaultBudget);
  const box = $("controls");
  for (const c of table.controls) {
    const row = document.createElement("div");
    row.className = "control";
    row.title = c.help;
    const id = `c-${c.name}`;
    const label = document.createElement("label");
    label.htmlFor = id;
    label.textContent = c.label;
    let input;
    if (c.kind === "choice") {
      input = document.createElement("select");
      for (const ch of c.choices) input.append(new Option(ch.label, ch.value));
    } else if (c.kind === "toggle") {
      input = document.createElement("input");
      input.type = "checkbox";
    } else if (c.name === "seed") {
      input = document.createElement("input");
      input.type = "number";
      Object.assign(input, { min: c.min, max: c.max, step: 1 });
    } else {
      input = document.createElement("input");
      input.type = "range";
      Object.assign(input, { min: c.min, max: c.max, step: c.step });
    }
    input.id = id;
    input.dataset.control = c.name;
    input.setAttribute("aria-describedby", `${id}-help`);
    const out = document.createElement("output");
    out.id = `${id}-out`;
    out.htmlFor = id;
    const help = document.createElement("span");
    help.id = `${id}-help`;
    help.className = "sr-only";
    help.textContent = `${c.help} Moves: ${c.moves.join("; ")}.`;
    input.addEventListener(c.kind === "toggle" || c.kind === "choice" ? "change" : "input", () => {
      showValue(c, input, out);
      if (edit) edit.moved = c;
      recordTree(c.name);
      scheduleEdit();
    });
    row.append(label, input, out, help);
    box.append(row);
  }
}

// the tree's undo steps: {from, to} (every control's value), a drag or a run of key
// presses on one control being one step
let treeSteps = [];
let treeRedo = [];
const MERGE_MS = 1500;
function controlValues() {
  const out = {};
  for (const c of table.controls) out[c.name] = controlValue(c);
  return out;
}
function setControls(values) {
  for (const c of table.controls) if (c.name in values) setControl(c, values[c.name]);
}
function recordTree(name) {
  if (!edit || !edit.initial) return;
  const now = controlValues();
  const last = treeSteps[treeSteps.length - 1];
  const t = performance.now();
  if (name && last && last.name === name && t - last.time < MERGE_MS && steps[steps.length - 1] === "tree") {
    last.to = now;
    last.time = t;
  } else {
    treeSteps.push({ from: edit.committed, to: now, name, time: t });
    treeRedo = [];
    noteStep("tree");
  }
  edit.committed = now;
}
function undoTree() {
  if (!edit || !edit.initial || !treeSteps.length) return;
  const step = treeSteps.pop();
  treeRedo.push(step);
  dropLast(steps, "tree");
  redoSteps.push("tree");
  setControls(step.from);
  edit.committed = step.from;
  edit.moved = null;
  scheduleEdit();
}
function redoTree() {
  if (!edit || !edit.initial || !treeRedo.length) return;
  const step = treeRedo.pop();
  step.time = 0; // never merged with a later step
  treeSteps.push(step);
  dropLast(redoSteps, "tree");
  steps.push("tree");
  setControls(step.to);
  edit.committed = step.to;
  edit.moved = null;
  scheduleEdit();
}
$("edit-undo").onclick = undoTree;
$("edit-redo").onclick = redoTree;

function controlValue(c) {
  const input = $(`c-${c.name}`);
  if (c.kind === "toggle") return input.checked;
  if (c.kind === "choice") return input.value;
  return Number(input.value);
}
function setControl(c, v) {
  const input = $(`c-${c.name}`);
  if (c.kind === "toggle") input.checked = Boolean(v);
  else if (c.name === "height") {
    // the range reaches past the tree's own height both ways
    input.max = String(Math.max(c.max, 3 * v).toFixed(1));
    input.value = String(v);
  } else input.value = String(v);
  showValue(c, input, $(`c-${c.name}-out`));
}
function showValue(c, input, out) {
  if (c.kind === "toggle") out.textContent = input.checked ? "on" : "off";
  else if (c.kind === "choice") out.textContent = "";
  else if (c.name === "seed") out.textContent = "";
  else out.textContent = `${Number(input.value).toFixed(c.step < 1 ? 2 : 0)}${c.unit === "x" ? "×" : ` ${c.unit}`}`;
}

async function treeRequest(controls, accept, maxFaces, fit = false) {
  // turned like the job's files, so an edit keeps the side the tree was drawn from
  const body = { params: edit.params, species: edit.species, controls, max_faces: maxFaces, yaw: edit.yaw, fit };
  return api("/trees", {
    method: "POST",
    body: JSON.stringify(body),
    headers: { "Content-Type": "application/json", Accept: accept },
  });
}

// ``switched``: a candidate species' tree, not the job's own (its downloads are grown)
async function startEdit(result, switched = false, cand = 0) {
  if (!table) return;
  const count = edit ? edit.count : 0;
  const mine = { params: result.params, species: result.species, yaw: result.yaw || 0, initial: null, busy: false, again: false, edited: false, switched, count, cand };
  edit = mine;
  // another tree: its own undo steps
  treeSteps = [];
  treeRedo = [];
  const r = await treeRequest({}, "application/json", table.view_faces);
  if (!r.ok || edit !== mine) return;
  const body = await r.json();
  if (edit !== mine) return;
  edit.initial = body.controls;
  for (const c of table.controls) setControl(c, edit.initial[c.name]);
  edit.committed = controlValues();
  $("edit-panel").hidden = false;
  // the edits from the address (a reload, a shared link) once the tree they edit is here
  if (pending && shownJob && pending.job === shownJob.id && pending.cand === cand) {
    const values = {};
    for (const c of table.controls) {
      const v = pending.controls[c.name];
      if (v === undefined) continue;
      values[c.name] = c.kind === "toggle" ? v === "true" : c.kind === "choice" ? v : Number(v);
      if (c.kind !== "toggle" && c.kind !== "choice" && !Number.isFinite(values[c.name])) delete values[c.name];
    }
    pending = null;
    if (Object.keys(values).length) {
      setControls(values);
      edit.committed = controlValues();
      scheduleEdit();
    }
  }
  document.body.dataset.edit = "ready";
}

function endEdit() {
  edit = null;
  shownJob = null;
  switchCount++;
  $("candidates-panel").hidden = true;
  $("edit-panel").hidden = true;
  $("views-panel").hidden = true;
  clearOutlines();
  delete document.body.dataset.edit;
  updateSideButton();
}

// the controls that differ from the tree the drawing gave
function changedControls() {
  const out = {};
  for (const c of table.controls) {
    const v = controlValue(c);
    const was = edit.initial[c.name];
    // a slider snaps to its step: within half a step it still shows the tree's own value
    if (c.kind === "toggle" || c.kind === "choice" || c.name === "seed" ? v !== was : Math.abs(v - was) > c.step / 2) out[c.name] = v;
  }
  return out;
}

// at most one request in flight; the latest slider position wins
function scheduleEdit() {
  if (!edit || !edit.initial) return;
  clearTimeout(editTimer);
  document.body.dataset.editQueue = "busy";
  editTimer = setTimeout(() => { editTimer = null; runEdit(); }, 60);
}
// "idle" once the tree shown is the controls' last position: nothing waits on the timer,
// nothing is in flight, nothing is to follow (a script or test waits on it, not on a count
// that an earlier position's tree can raise)
function markEditQueue() {
  if (editTimer === null && !(edit && (edit.busy || edit.again))) document.body.dataset.editQueue = "idle";
}
async function runEdit() {
  const mine = edit;
  if (!mine) { markEditQueue(); return; }
  if (mine.busy) { mine.again = true; return; }
  mine.busy = true;
  const t0 = performance.now();
  const controls = changedControls();
  // past the generator's limits the slider being dragged stops at the most it can grow
  // (another kind of control: every slider moved comes back by one fraction)
  const moved = mine.moved;
  const fit = moved && moved.kind === "number" && moved.neutral !== null ? [moved.name] : true;
  try {
    const r = await treeRequest(controls, "model/gltf-binary", table.view_faces, fit);
    if (edit !== mine) return; // switched to another tree meanwhile
    if (!r.ok) {
      const body = await r.json().catch(() => ({}));
      $("edit-status").textContent = `Refused: ${body.detail || r.statusText}`;
    } else {
      const buffer = await r.arrayBuffer();
      if (edit !== mine) return;
      loadModel(buffer, "refit"); // a wider or taller tree stays in view
      edit.edited = Object.keys(controls).length > 0;
      edit.count += 1;
      document.body.dataset.edits = String(edit.count);
      setPreset(!edit.edited && !edit.switched);
      updateSideButton();
      const adjusted = JSON.parse(r.headers.get("X-Tree-Adjusted") || "{}");
      const notes = [];
      for (const [name, v] of Object.entries(adjusted)) {
        const c = table.controls.find((x) => x.name === name);
        if (!c) continue;
        setControl(c, v);
        notes.push(`${c.label.toLowerCase()} held at ${v} (the generator's limit)`);
      }
      $("edit-status").textContent = [`${Math.round(performance.now() - t0)} ms`, ...notes].join(" · ");
      $("view-note").textContent = edit.edited ? "edited" : "";
      updateUrl();
    }
  } finally {
    mine.busy = false;
    if (mine.again && edit === mine) { mine.again = false; runEdit(); } else markEditQueue();
  }
}

$("variant").onclick = () => {
  if (!edit || !table) return;
  const seed = table.controls.find((c) => c.name === "seed");
  setControl(seed, Math.floor(Math.random() * seed.max));
  recordTree(null);
  scheduleEdit();
};
$("reset-controls").onclick = () => {
  if (!edit || !edit.initial) return;
  for (const c of table.controls) setControl(c, edit.initial[c.name]);
  recordTree(null);
  scheduleEdit();
};

// the downloads of an edited tree or another candidate's: asked for when clicked (full
// detail for the GLB)
async function downloadEdited(ev, accept, ext, light = false, always = false) {
  if (!edit || !edit.initial) { if (always) ev.preventDefault(); return; }
  if (!always && !(edit.edited || edit.switched)) return; // the job's own file
  ev.preventDefault();
  const name = `tree_${edit.species}${edit.edited ? "_edited" : ""}${light ? "_light" : ""}.${ext}`;
  // full detail (at the job's own triangle budget), or the 3D view's light tree
  const faces = light ? table.view_faces : ((shownJob && shownJob.options) || {}).max_faces ?? null;
  $("edit-status").textContent = `Preparing ${name}...`;
  const r = await treeRequest(changedControls(), accept, faces);
  if (!r.ok) { $("edit-status").textContent = `Download failed (${r.status})`; return; }
  const blob = accept === "application/json"
    ? new Blob([JSON.stringify((await r.json()).params, null, 1)], { type: "application/json" })
    : await r.blob();
  const a = document.createElement("a");
  a.href = URL.createObjectURL(blob);
  a.download = name;
  a.click();
  setTimeout(() => URL.revokeObjectURL(a.href), 10_000);
  $("edit-status").textContent = "";
}
$("dl-glb").addEventListener("click", (ev) => downloadEdited(ev, "model/gltf-binary", "glb"));
$("dl-glb-light").addEventListener("click", (ev) => downloadEdited(ev, "model/gltf-binary", "glb", true));
$("dl-obj").addEventListener("click", (ev) => downloadEdited(ev, "application/zip", "obj.zip", false, true));
$("dl-json").addEventListener("click", (ev) => downloadEdited(ev, "application/json", "json"));

// ---- the 3D view ---------------------------------------------------------------------
const view = $("view");
let renderer = null, scene = null, camera = null, controls = null, model = null, ground = null;
let framedJob = null; // the job whose tree the camera was framed on
let turnedByHand = false; // the person moved the camera since it was last framed
// frame a job's newer tree (a better one while refining, the final one) unless the person
// has turned the view to look at it: then the camera stays where they put it
function frameFor(job) { return framedJob !== job.id || !turnedByHand; }

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
  // the ground: a disc at the tree's base (y = 0 in the GLB), sized to the tree
  ground = new THREE.Mesh(
    new THREE.CircleGeometry(1, 48),
    new THREE.MeshLambertMaterial({ color: 0x9fb58f, side: THREE.DoubleSide }),
  );
  ground.rotation.x = -Math.PI / 2;
  ground.visible = $("ground").checked;
  scene.add(ground);
  camera = new THREE.PerspectiveCamera(40, 1, 0.01, 1000);
  controls = new OrbitControls(camera, renderer.domElement);
  controls.addEventListener("change", () => { render(); showTurn(); });
  controls.addEventListener("start", () => { turnedByHand = true; });
  // a vertical swipe scrolls the page (a phone); a sideways one turns the tree
  renderer.domElement.style.touchAction = "pan-y";
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

// look at the whole tree from the front, a little above
function frameModel() {
  if (!model) return;
  const box = new THREE.Box3().setFromObject(model);
  const size = box.getSize(new THREE.Vector3());
  const centre = box.getCenter(new THREE.Vector3());
  const dist = (Math.max(size.y, size.x, size.z) / 2 / Math.tan((camera.fov * Math.PI) / 360)) * 1.25;
  camera.position.set(centre.x, centre.y + size.y * 0.1, centre.z + dist);
  camera.near = dist / 100; camera.far = dist * 10;
  camera.updateProjectionMatrix();
  controls.target.copy(centre);
  controls.update();
  turnedByHand = false;
  render();
}
$("reset-view").onclick = () => frameModel();
// the tree changed size (an edit): the same direction, near enough to see all of it
function refitModel() {
  if (!model) return;
  if (!turnedByHand) { frameModel(); return; }
  const box = new THREE.Box3().setFromObject(model);
  const size = box.getSize(new THREE.Vector3());
  const centre = box.getCenter(new THREE.Vector3());
  const dist = (Math.max(size.y, size.x, size.z) / 2 / Math.tan((camera.fov * Math.PI) / 360)) * 1.25;
  const dir = camera.position.clone().sub(controls.target).normalize();
  camera.position.copy(centre).addScaledVector(dir, dist);
  camera.near = dist / 100; camera.far = dist * 10;
  camera.updateProjectionMatrix();
  controls.target.copy(centre);
  controls.update();
  turnedByHand = true;
  render();
}
$("ground").onchange = () => { if (ground) { ground.visible = $("ground").checked; render(); } };

// ``source``: a URL or the bytes of a GLB (an edit's answer); ``frame``: move the camera
// (true), keep it (false) or fit the tree again from where it looks ("refit")
function loadModel(source, frame = true) {
  if (!renderer) setupView();
  document.body.dataset.model = "loading";
  const onLoad = (gltf) => {
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
    const box = new THREE.Box3().setFromObject(model);
    const size = box.getSize(new THREE.Vector3());
    ground.scale.setScalar(Math.max(size.x, size.z, size.y * 0.5) * 0.75);
    ground.position.set((box.min.x + box.max.x) / 2, box.min.y - size.y * 0.002, (box.min.z + box.max.z) / 2);
    $("height-readout").textContent = `${size.y.toFixed(size.y < 10 ? 2 : 1)} m`;
    if (frame === "refit") refitModel();
    else if (frame) frameModel();
    else { render(); showTurn(); }
    document.body.dataset.meshes = String(meshes);
    document.body.dataset.loads = String(Number(document.body.dataset.loads || 0) + 1);
    document.body.dataset.model = "loaded";
    updateSideButton();
  };
  const onError = (err) => {
    document.body.dataset.model = "failed";
    say(`The 3D view cannot load the tree: ${err.message || err}`);
  };
  if (typeof source === "string") new GLTFLoader().load(source, onLoad, undefined, onError);
  else new GLTFLoader().parse(source, "", onLoad, onError);
}

// ---- drawing the tree from another side ------------------------------------------------
const MAX_VIEWS = 4; // treesketch.views.MAX_VIEWS: drawings of one tree in one job
const VIEWS_KEY = "treesketch.views"; // this tab's drawings of its latest jobs (a reload keeps them)
const sentViews = new Map(); // job id -> the drawings sent: [{blob, yaw}], the first at 0
let side = null; // drawing from another side: {job, turn, views, strokes, undone}

// the 3D view's turn about the tree, degrees from the first drawing's side; positive:
// the camera went round to its right.  A job's GLBs are turned to face the first drawing
// (ExportOptions.face_view: the default front view shows the tree as drawn), and a camera
// gone round by +t sees what SketchRenderer draws at the result's yaw + t: the drawing's
// "yaw".  A tree grown by POST /trees (an edit, a candidate) is turned the same way.
function currentTurn() {
  const dx = camera.position.x - controls.target.x;
  const dz = camera.position.z - controls.target.z;
  let t = (Math.atan2(dx, dz) * 180) / Math.PI;
  t = ((t % 360) + 540) % 360 - 180; // -180 <= t < 180
  t = Math.round(t * 10) / 10;
  return t === 0 ? 0 : t; // never -0
}
// a turn in words: -180 < t <= 180, signed
function turnText(t) {
  let d = (((t % 360) + 360) % 360);
  if (d > 180) d -= 360;
  if (Math.abs(d) < 0.05) return "the front (0°)";
  return `${d > 0 ? "+" : "−"}${Math.abs(d).toFixed(Math.abs(d) % 1 ? 1 : 0)}°`;
}
function showTurn() { $("turn-readout").textContent = model ? turnText(currentTurn()) : "-"; }

// walk round the tree by ``deg`` degrees (positive: to the right), for the keyboard
function walk(deg) {
  if (!model) return;
  const off = camera.position.clone().sub(controls.target);
  off.applyAxisAngle(new THREE.Vector3(0, 1, 0), (deg * Math.PI) / 180);
  camera.position.copy(controls.target).add(off);
  controls.update();
  turnedByHand = true;
}
$("turn-left").onclick = () => walk(-15);
$("turn-right").onclick = () => walk(15);

// why the shown tree cannot be drawn from another side now, or null
function sideProblem() {
  if (!shownJob) return "Make a tree first, then turn it and draw it from another side";
  const views = sentViews.get(shownJob.id);
  if (!views) return "This tree's drawing is not kept in this tab: draw it and make the tree again to add another side";
  if (views.length >= MAX_VIEWS) return `A tree takes at most ${MAX_VIEWS} drawings`;
  if (edit && (edit.edited || edit.switched)) return "Show the drawing's own tree (the first candidate, controls reset) to draw it from another side";
  if (!model || document.body.dataset.model !== "loaded") return "Wait for the 3D tree";
  return null;
}
const SIDE_TITLE = $("draw-side").title;
function updateSideButton() {
  const why = sideProblem();
  $("draw-side").disabled = Boolean(why) || side !== null;
  $("draw-side").title = why || SIDE_TITLE;
}

$("draw-side").onclick = () => {
  if (sideProblem() || side) return;
  const job = shownJob;
  const turn = currentTurn();
  const views = sentViews.get(job.id);
  side = { job: job.id, turn, views, strokes, undone };
  strokes = [];
  undone = [];
  redraw();
  document.body.dataset.mode = "side";
  document.body.dataset.turn = String(turn);
  document.body.dataset.guide = "loading";
  const guide = $("guide");
  guide.hidden = true;
  guide.onload = () => { if (side) { guide.hidden = false; document.body.dataset.guide = "loaded"; } };
  guide.onerror = () => { document.body.dataset.guide = "failed"; say("The tree's outline from this side could not be drawn: draw the side anyway."); };
  guide.src = `/jobs/${job.id}/outline.png?turn=${turn}&size=512`;
  $("side-note").textContent = `Drawing ${views.length + 1}: the tree seen from ${turnText(turn)}, its outline shown faintly. Draw over it, then press "Make the tree": ${views.length === 1 ? "both drawings go" : "all the drawings go"} together.`;
  $("side-bar").hidden = false;
  say(`Draw the tree as seen from ${turnText(turn)}.`);
  updateSideButton();
  if (phone()) $("draw-panel").scrollIntoView({ behavior: "smooth" });
};

// back to drawing one view; ``restore``: the pad shows what it had before
function leaveSide(restore) {
  if (!side) return;
  if (restore) { strokes = side.strokes; undone = side.undone; redraw(); }
  side = null;
  if (restore) savePad();
  $("guide").hidden = true;
  $("guide").removeAttribute("src");
  $("side-bar").hidden = true;
  delete document.body.dataset.mode;
  delete document.body.dataset.turn;
  delete document.body.dataset.guide;
  updateSideButton();
}
$("side-exit").onclick = () => { leaveSide(true); say("Back to the first drawing."); $("draw-side").focus(); };

// the result's views: the refined tree's sketch from each drawing's side
function showViews(job) {
  const views = job.result.views || [];
  const box = $("views");
  box.replaceChildren();
  views.forEach((v, i) => {
    const fig = document.createElement("figure");
    const im = document.createElement("img");
    im.src = i === 0 ? job.links["sketch_after.png"] : job.links[`view${i + 1}_after.png`];
    im.alt = `Sketch of the refined tree from the side of drawing ${i + 1}`;
    const cap = document.createElement("figcaption");
    const where = i === 0 ? "the front" : turnText(v.yaw) + (v.searched ? " (found)" : "");
    cap.textContent = `drawing ${i + 1}: ${where}, distance ${v.loss_after.toFixed(3)}`;
    fig.append(im, cap);
    box.append(fig);
  });
  $("views-panel").hidden = views.length < 2;
  document.body.dataset.views = String(Math.max(1, views.length));
}

// the drawing's outline (red) over the tree's (blue), one picture per drawn view (GET
// /jobs/{id}/outlines.png?view=N): does the tree follow what was drawn?  It is the job's
// own tree: an edit or another species on show is not outlined.  A figure shows once its
// picture has loaded; one that cannot load (a job from before these pictures, files
// expired, a lost connection) is dropped, so no broken-image icon, and the rest stays.
const OUTLINES_CAPTION = "your drawing's outline (red) over the tree's (blue)";
function clearOutlines() {
  $("outlines").replaceChildren();
  $("outlines-panel").hidden = true;
  delete document.body.dataset.outlines;
}
function showOutlines(job) {
  clearOutlines();
  const url = job.links["outlines.png"];
  if (!url) return;
  const box = $("outlines");
  const n = Math.max(1, (job.result.views || []).length);
  for (let i = 1; i <= n; i++) {
    const fig = document.createElement("figure");
    fig.hidden = true;
    fig.title = "The tree the drawing gave, seen from where it was drawn (edits are not outlined)";
    const im = document.createElement("img");
    im.alt = `Drawing ${i}'s outline in red over the tree's outline in blue, seen from the same side`;
    im.onload = () => {
      if (!fig.isConnected) return; // another job came on show meanwhile
      fig.hidden = false;
      $("outlines-panel").hidden = false;
      document.body.dataset.outlines = String(box.querySelectorAll("figure:not([hidden])").length);
    };
    im.onerror = () => fig.remove();
    const cap = document.createElement("figcaption");
    cap.textContent = n > 1 ? `drawing ${i}: ${OUTLINES_CAPTION}` : OUTLINES_CAPTION;
    fig.append(im, cap);
    box.append(fig);
    im.src = `${url}?view=${i}`;
  }
}

// the drawings of a job kept in this tab (sessionStorage, the latest few jobs) so that a
// reload can still add a side; in memory only when the storage is full or off
const blobData = (blob) => new Promise((ok, fail) => {
  const r = new FileReader();
  r.onload = () => ok(r.result);
  r.onerror = () => fail(r.error);
  r.readAsDataURL(blob);
});
function dataBlob(url) {
  const [head, b64] = url.split(",");
  const bytes = Uint8Array.from(atob(b64), (c) => c.charCodeAt(0));
  return new Blob([bytes], { type: head.slice(5).split(";")[0] });
}
async function keepViews(id, views) {
  try {
    const pngs = await Promise.all(views.map((v) => blobData(v.blob)));
    const all = JSON.parse(sessionStorage.getItem(VIEWS_KEY) || "{}");
    all[id] = views.map((v, i) => ({ png: pngs[i], yaw: v.yaw }));
    const ids = Object.keys(all);
    for (const old of ids.slice(0, Math.max(0, ids.length - 6))) delete all[old];
    sessionStorage.setItem(VIEWS_KEY, JSON.stringify(all));
  } catch { /* kept in memory only */ }
}
function restoreViews(id) {
  try {
    const kept = JSON.parse(sessionStorage.getItem(VIEWS_KEY) || "{}")[id];
    if (kept) sentViews.set(id, kept.map((v) => ({ blob: dataBlob(v.png), yaw: v.yaw })));
  } catch { /* none kept */ }
}
// a finished job opened by its link in another tab: its drawings from the server (GET
// /jobs/{id}/drawing.png), each with its turn (the one searched for where none was given)
async function fetchViews(job) {
  if (sentViews.has(job.id) || job.state !== "done") return;
  const yaws = [0, ...((job.options || {}).yaws || [])];
  const found = (job.result.views || []).map((v) => v.yaw);
  try {
    const blobs = await Promise.all(yaws.map(async (_, i) => {
      const r = await api(`/jobs/${encodeURIComponent(job.id)}/drawing.png?view=${i + 1}`);
      if (!r.ok) throw new Error(String(r.status));
      return r.blob();
    }));
    const views = blobs.map((blob, i) => ({ blob, yaw: yaws[i] ?? found[i] ?? 0 }));
    sentViews.set(job.id, views);
    keepViews(job.id, views);
    updateSideButton();
  } catch { /* the drawings are gone: no other side from here */ }
}

// ---- start ---------------------------------------------------------------------------
Promise.all([loadControls(), loadSpecies()]).then(restoreFromUrl);
loadGallery();
refreshRecent();
