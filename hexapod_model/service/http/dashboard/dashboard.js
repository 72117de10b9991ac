// The fixtures' dashboard: reads the service's server-sent events (GET /events) and renders every
// fixture's state, pose, target, deviation, per-leg changes, clearance and flags. No build step, no external
// resource. The bearer token (when the service needs one) comes from the page's #token=... and is
// kept in this tab's sessionStorage; it is sent as an Authorization header, never in a URL.
// "In tolerance" is green only for a locked fixture whose ok pose is in tolerance: a plate that
// passes through the tolerance while it moves shows amber. With #measure in the address (for the
// layout tests) each rendered value also carries its computed font size, box and colour.
"use strict";

const PERIOD_MS = 1000;  // reconnect delay
const MIN_SCALE_MM = 0.5;  // the leg bars' half-scale: the smallest of 1-2-5 steps above the largest change, at least this
const MEASURE = /(^|[#&])measure(&|$)/.test(location.hash);  // read before token() clears the address's hash

function token() {
  const m = location.hash.match(/token=([^&]+)/);
  if (m) {
    sessionStorage.setItem("hexapod-token", decodeURIComponent(m[1]));
    history.replaceState(null, "", location.pathname);
  }
  return sessionStorage.getItem("hexapod-token");
}

function headers() {
  const t = token();
  return t ? { Authorization: "Bearer " + t } : {};
}

function fmt(v, digits) {
  return v === null || v === undefined ? "\u2013" : Number(v).toFixed(digits);
}

function el(tag, attrs, text) {
  const e = document.createElement(tag);
  for (const [k, v] of Object.entries(attrs || {})) e.setAttribute(k, v);
  if (text !== undefined) e.textContent = text;
  return e;
}

// a shown value: formatted (its magnitude only when `magnitude`), the number itself in data-value
function value(name, field, v, digits, magnitude) {
  const shown = magnitude && v !== null && v !== undefined ? Math.abs(v) : v;
  const attrs = { "data-fixture": name, "data-field": field, "data-value": v === null || v === undefined ? "" : String(v) };
  return el("span", attrs, fmt(shown, digits));
}

// the bars' half-scale (mm): 0.5, 1, 2, 5, 10, 20, ... at least the largest change
function scaleMm(legs) {
  const largest = Math.max(0, ...legs.map((l) => Math.abs(l.change_mm || 0)));
  let scale = MIN_SCALE_MM;
  for (let k = 0; scale < largest; k++) scale = [1, 2, 5][k % 3] * Math.pow(10, Math.floor(k / 3));
  return scale;
}

// "yes" (green): locked, ok and in tolerance; "wait": in tolerance but not locked yet; "no"
function toleranceState(g) {
  if (!g.in_tolerance) return "no";
  return g.status === "ok" && g.state === "locked" ? "yes" : "wait";
}

function displayState(g) {
  if (g.status !== "ok" && g.status !== "flagged" && g.status !== "drift") return "fault";
  return g.state;
}

function poseTable(name, rows) {
  const table = el("table");
  const head = el("tr");
  for (const h of ["", "x mm", "y mm", "z mm", "roll \u00b0", "pitch \u00b0", "yaw \u00b0"]) head.appendChild(el("th", {}, h));
  table.appendChild(head);
  for (const [label, key, pose] of rows) {
    const tr = el("tr");
    tr.appendChild(el("td", {}, label));
    for (const k of ["x", "y", "z"]) {
      const td = el("td");
      td.appendChild(value(name, key + "." + k + "_mm", pose ? pose[k] * 1000 : null, 3));
      tr.appendChild(td);
    }
    for (const k of ["roll", "pitch", "yaw"]) {
      const td = el("td");
      td.appendChild(value(name, key + "." + k + "_deg", pose ? pose[k] : null, 3));
      tr.appendChild(td);
    }
    table.appendChild(tr);
  }
  return table;
}

// the clearance of the pose and of the target: the smallest distance between two bodies (mm) and the
// pair; a collision (below min_clearance) is highlighted
function clearances(name, g) {
  const box = el("div", { class: "section detail clearance" });
  for (const [label, key, c] of [["clearance", "clearance", g.clearance], ["target", "target_clearance", g.target_clearance]]) {
    const part = el("span", { class: "part" + (c && c.collision ? " collision" : ""), "data-fixture": name, "data-field": key + ".collision", "data-value": c ? String(c.collision) : "" });
    part.appendChild(document.createTextNode(label + " "));
    part.appendChild(value(name, key + ".distance_mm", c ? c.distance_mm : null, 3));
    part.appendChild(document.createTextNode(" mm"));
    if (c) {
      const pair = c.pair.join(" \u2013 ");
      part.appendChild(document.createTextNode(" ("));
      part.appendChild(el("span", { "data-fixture": name, "data-field": key + ".pair", "data-value": c.pair.join(",") }, pair));
      part.appendChild(document.createTextNode(")" + (c.collision ? " collision" : "")));
    }
    box.appendChild(part);
  }
  return box;
}

function legBars(name, legs) {
  const box = el("div", { class: "section legs" });
  const scale = scaleMm(legs);
  const head = el("div", { class: "row" });
  head.appendChild(el("span", { class: "leg" }));
  const ruler = el("div", { class: "scale", "data-fixture": name, "data-field": "legs.scale_mm", "data-value": String(scale) });
  ruler.title = "a full half-bar is " + scale + " mm: left retract, right extend";
  ruler.appendChild(el("span", { class: "lo" }, "\u2212" + scale));
  ruler.appendChild(el("span", { class: "zero" }, "0"));
  ruler.appendChild(el("span", { class: "hi" }, "+" + scale + " mm"));
  head.appendChild(ruler);
  box.appendChild(head);
  for (const l of legs) {
    const row = el("div", { class: "row" });
    row.appendChild(el("span", { class: "leg" }, "leg " + l.leg));
    const bar = el("div", { class: "bar", title: "reading " + fmt(l.reading_mm, 3) + " mm, target " + fmt(l.target_mm, 3) + " mm" });
    bar.appendChild(el("div", { class: "mid" }));
    if (l.change_mm !== null) {
      const w = Math.min(50, (50 * Math.abs(l.change_mm)) / scale);
      const fill = el("div", { class: "fill" + (l.change_mm < 0 ? " retract" : "") });
      fill.style.left = (l.change_mm < 0 ? 50 - w : 50) + "%";
      fill.style.width = w + "%";
      bar.appendChild(fill);
    }
    row.appendChild(bar);
    const way = l.change_mm === null ? "none" : l.change_mm >= 0 ? "extend" : "retract";
    const text = el("span", { class: "change " + way });
    text.appendChild(el("span", { class: "arrow" }, way === "none" ? "" : way === "extend" ? "\u25b6" : "\u25c0"));
    const number = value(name, "legs." + l.leg + ".change_mm", l.change_mm, 3, true);
    number.setAttribute("class", "value");
    text.appendChild(number);
    text.appendChild(el("span", { class: "unit" }, "mm"));
    text.appendChild(value(name, "legs." + l.leg + ".target_mm", l.target_mm, 3));
    text.lastChild.hidden = true;
    text.appendChild(el("span", { class: "word" }, way === "none" ? "no reading" : way));
    row.appendChild(text);
    box.appendChild(row);
  }
  return box;
}

// POST /fixtures/NAME/acknowledge {"by", "note"}: who checked the fixture and what they found
async function acknowledge(name, button) {
  const by = window.prompt("Acknowledge the fault of " + name + ": your name");
  if (!by) return;
  const note = window.prompt("What did you check or repair?") || "";
  button.disabled = true;
  button.setAttribute("data-busy", "1");
  try {
    const r = await fetch("/fixtures/" + encodeURIComponent(name) + "/acknowledge", {
      method: "POST",
      headers: Object.assign({ "Content-Type": "application/json" }, headers()),
      body: JSON.stringify({ by: by, note: note }),
    });
    const answer = await r.json().catch(() => ({}));
    button.textContent = r.ok ? "acknowledged" : "not acknowledged: " + (answer.error || r.status);
  } catch (e) {
    button.textContent = "not acknowledged: " + e;
  }
  setTimeout(() => { button.removeAttribute("data-busy"); button.textContent = "Acknowledge"; }, 4000);
}

function card(g) {
  const name = g.fixture;
  const c = el("section", { class: "card", id: "fixture-" + name, "data-fixture": name });
  const h = el("h2", {}, name);
  const state = displayState(g);
  h.appendChild(el("span", { class: "badge " + state, "data-fixture": name, "data-field": "state" }, state));
  h.appendChild(el("span", { class: "badge", "data-fixture": name, "data-field": "status" }, g.status));
  const tol = toleranceState(g);
  const words = { yes: "in tolerance", wait: "in tolerance, not locked", no: "not in tolerance" };
  const badge = { class: "badge " + tol, "data-fixture": name, "data-field": "in_tolerance", "data-value": String(g.in_tolerance) };
  h.appendChild(el("span", badge, words[tol]));
  c.appendChild(h);
  const big = el("div", { class: "deviation" });
  for (const [label, field, v, digits, unit] of [
    ["deviation", "deviation.translation_mm", g.deviation ? g.deviation.translation_mm : null, 3, "mm"],
    ["rotation", "deviation.rotation_deg", g.deviation ? g.deviation.rotation_deg : null, 4, "\u00b0"],
  ]) {
    const part = el("div");
    part.appendChild(el("span", { class: "label" }, label));
    const number = value(name, field, v, digits);
    number.setAttribute("class", "big");
    part.appendChild(number);
    part.appendChild(el("span", { class: "unit" }, unit));
    big.appendChild(part);
  }
  c.appendChild(big);
  const dev = el("div", { class: "detail" });
  dev.appendChild(document.createTextNode("tolerance "));
  dev.appendChild(value(name, "tolerance.translation_mm", g.target ? g.target.tolerance.translation_mm : null, 3));
  dev.appendChild(document.createTextNode(" mm, "));
  dev.appendChild(value(name, "tolerance.rotation_deg", g.target ? g.target.tolerance.rotation_deg : null, 3));
  dev.appendChild(document.createTextNode("\u00b0; sigma "));
  dev.appendChild(value(name, "sigma.translation_mm", g.sigma ? g.sigma.translation_mm : null, 4));
  dev.appendChild(document.createTextNode(" mm"));
  if (g.target && g.target.recipe) dev.appendChild(document.createTextNode(" (recipe " + g.target.recipe + ")"));
  c.appendChild(dev);
  if (g.legs.length) c.appendChild(legBars(name, g.legs));
  const target = g.target ? g.target.pose : null;
  const pose = el("div", { class: "section pose" });
  pose.appendChild(poseTable(name, [["pose", "pose", g.pose], ["target", "target", target]]));
  c.appendChild(pose);
  c.appendChild(clearances(name, g));
  const flags = el("div", { class: "section flags", "data-fixture": name, "data-field": "flags" }, g.flags.join(", "));
  c.appendChild(flags);
  if (g.target_problem) c.appendChild(el("div", { class: "flags" }, g.target_problem));
  const button = el("button", { type: "button", "data-fixture": name, "data-field": "acknowledge" }, "Acknowledge");
  button.disabled = g.status !== "unacknowledged_fault";  // a latched fault waits for a person
  button.title = button.disabled ? "no fault waits for an acknowledgement" : "acknowledge the fault (needs the token)";
  button.addEventListener("click", () => acknowledge(name, button));
  c.appendChild(button);
  return c;
}

// a playing changeover plan: its phase, the fixture the robot serves, how far (bar) and a coupling mismatch
function planProgress(plan) {
  const box = document.getElementById("plan");
  box.hidden = !plan;
  box.replaceChildren();
  if (!plan) return;
  const m = plan.coupling_mismatch;
  box.className = "plan" + (m ? " mismatch" : "");
  box.appendChild(document.createTextNode("plan: "));
  box.appendChild(el("strong", { "data-field": "plan.phase", "data-value": plan.phase }, plan.phase));
  if (plan.fixture) box.appendChild(el("span", { "data-field": "plan.fixture", "data-value": plan.fixture }, " " + plan.fixture));
  const bar = el("progress", { max: "1", "data-field": "plan.fraction", "data-value": plan.fraction === null ? "" : String(plan.fraction) });
  bar.value = plan.fraction || 0;
  box.appendChild(bar);
  box.appendChild(value(null, "plan.t_s", plan.t_s, 1));
  box.lastChild.removeAttribute("data-fixture");
  box.appendChild(document.createTextNode(" / " + fmt(plan.total_s, 1) + " s"));
  if (m) {
    const text = "coupling_mismatch: " + m.fixture + " (" + m.phase + ") " + fmt(m.translation_mm, 3) + " mm, " + fmt(m.rotation_deg, 3) + "\u00b0";
    box.appendChild(el("span", { class: "flags", "data-field": "plan.coupling_mismatch", "data-value": m.fixture }, " " + text));
  }
}

function render(overview) {
  document.getElementById("active-recipe").textContent = overview.active_recipe || "\u2013";
  planProgress(overview.plan);
  const main = document.getElementById("fixtures");
  for (const g of overview.fixtures) {
    const fresh = card(g);
    const old = document.getElementById("fixture-" + g.fixture);
    if (old) {
      const button = old.querySelector("button");
      if (button && button.hasAttribute("data-busy")) fresh.replaceChild(button, fresh.querySelector("button"));
      main.replaceChild(fresh, old);
    } else {
      main.appendChild(fresh);
    }
  }
  document.body.setAttribute("data-updated", String(overview.t));
  if (MEASURE) measure();
}

// #measure: each value, badge and card carries its computed font size (px), box (x,y,w,h px) and
// background colour; the body the viewport's width and the page's scroll width
function measure() {
  for (const e of document.querySelectorAll("[data-field], .card")) {
    const style = getComputedStyle(e);
    const r = e.getBoundingClientRect();
    e.setAttribute("data-font-px", style.fontSize.replace("px", ""));
    e.setAttribute("data-box", [r.left, r.top, r.width, r.height].map((v) => v.toFixed(1)).join(","));
    e.setAttribute("data-bg", style.backgroundColor);
  }
  document.body.setAttribute("data-viewport", String(window.innerWidth));
  document.body.setAttribute("data-scroll-width", String(document.documentElement.scrollWidth));
}

function status(text) {
  document.getElementById("connection").textContent = text;
}

async function follow() {
  for (;;) {
    try {
      const r = await fetch("/events", { headers: headers(), cache: "no-store" });
      if (r.status === 401) {
        status("the service needs its token: open this page as /#token=TOKEN");
      } else if (!r.ok) {
        status("service answered " + r.status);
      } else {
        status("live");
        const reader = r.body.getReader();
        const decoder = new TextDecoder();
        let buffer = "";
        for (;;) {
          const { value: chunk, done } = await reader.read();
          if (done) break;
          buffer += decoder.decode(chunk, { stream: true });
          let end;
          while ((end = buffer.indexOf("\n\n")) >= 0) {
            const event = buffer.slice(0, end);
            buffer = buffer.slice(end + 2);
            const data = event.split("\n").filter((l) => l.startsWith("data: ")).map((l) => l.slice(6)).join("\n");
            if (data) render(JSON.parse(data));
          }
        }
        status("disconnected; reconnecting");
      }
    } catch (e) {
      status("disconnected (" + e + "); reconnecting");
    }
    await new Promise((resolve) => setTimeout(resolve, PERIOD_MS));
  }
}

follow();
