// The fixtures' dashboard: reads the service's server-sent events (GET /events) and renders every
// fixture's state, pose, target, deviation, per-leg changes and flags. No build step, no external
// resource. The bearer token (when the service needs one) comes from the page's #token=... and is
// kept in this tab's sessionStorage; it is sent as an Authorization header, never in a URL.
"use strict";

const PERIOD_MS = 1000;  // reconnect delay
const BAR_MM = 5.0;      // a full half-bar is this change (mm) or the largest change shown, whichever is larger

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

function legBars(name, legs) {
  const box = el("div", { class: "section legs" });
  const largest = Math.max(BAR_MM, ...legs.map((l) => Math.abs(l.change_mm || 0)));
  for (const l of legs) {
    const row = el("div", { class: "row" });
    row.appendChild(el("span", {}, "leg " + l.leg));
    const bar = el("div", { class: "bar", title: "reading " + fmt(l.reading_mm, 3) + " mm, target " + fmt(l.target_mm, 3) + " mm" });
    bar.appendChild(el("div", { class: "mid" }));
    if (l.change_mm !== null) {
      const w = (50 * Math.abs(l.change_mm)) / largest;
      const fill = el("div", { class: "fill" + (l.change_mm < 0 ? " retract" : "") });
      fill.style.left = (l.change_mm < 0 ? 50 - w : 50) + "%";
      fill.style.width = w + "%";
      bar.appendChild(fill);
    }
    row.appendChild(bar);
    const text = el("span");
    text.appendChild(document.createTextNode(l.change_mm === null ? "no reading " : (l.change_mm >= 0 ? "extend " : "retract ")));
    text.appendChild(value(name, "legs." + l.leg + ".change_mm", l.change_mm, 3, true));
    text.appendChild(document.createTextNode(" mm"));
    text.appendChild(value(name, "legs." + l.leg + ".target_mm", l.target_mm, 3));
    text.lastChild.hidden = true;
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
  const tol = g.in_tolerance ? "in tolerance" : "not in tolerance";
  h.appendChild(el("span", { class: "badge " + (g.in_tolerance ? "yes" : "no"), "data-fixture": name, "data-field": "in_tolerance" }, tol));
  c.appendChild(h);
  const target = g.target ? g.target.pose : null;
  c.appendChild(poseTable(name, [["pose", "pose", g.pose], ["target", "target", target]]));
  const dev = el("div", { class: "section" });
  dev.appendChild(document.createTextNode("deviation "));
  dev.appendChild(value(name, "deviation.translation_mm", g.deviation ? g.deviation.translation_mm : null, 3));
  dev.appendChild(document.createTextNode(" mm, "));
  dev.appendChild(value(name, "deviation.rotation_deg", g.deviation ? g.deviation.rotation_deg : null, 4));
  dev.appendChild(document.createTextNode("\u00b0; tolerance "));
  dev.appendChild(value(name, "tolerance.translation_mm", g.target ? g.target.tolerance.translation_mm : null, 3));
  dev.appendChild(document.createTextNode(" mm, "));
  dev.appendChild(value(name, "tolerance.rotation_deg", g.target ? g.target.tolerance.rotation_deg : null, 3));
  dev.appendChild(document.createTextNode("\u00b0; sigma "));
  dev.appendChild(value(name, "sigma.translation_mm", g.sigma ? g.sigma.translation_mm : null, 4));
  dev.appendChild(document.createTextNode(" mm"));
  if (g.target && g.target.recipe) dev.appendChild(document.createTextNode(" (recipe " + g.target.recipe + ")"));
  c.appendChild(dev);
  if (g.legs.length) c.appendChild(legBars(name, g.legs));
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
