/* cassi-farm rating session: one blinded cell at a time (the task viewer in a frame), a rating on
   the thesis's scale, the faults ticked; progress in localStorage under the session's id; the
   ratings exported as CSV (the columns cassi agree reads).
   Data: window.CASSI_SESSION (written by cassi.reports.rating_session). Strings from the data
   are only ever set as text, never as HTML. */
(function () {
  "use strict";
  const S = window.CASSI_SESSION;
  const $ = (id) => document.getElementById(id);
  const status = $("status");
  const STORE = "cassi-rate:" + (S ? S.session : "");

  function say(text, error) { status.textContent = text; status.className = error ? "error" : "meta"; }

  function load() {
    try {
      const x = JSON.parse(localStorage.getItem(STORE) || "null");
      if (x && typeof x === "object" && x.answers) return x;
    } catch (e) { /* a damaged entry starts afresh */ }
    return { rater: "", current: 0, answers: {} };
  }
  const state = S ? load() : null;
  function save() { localStorage.setItem(STORE, JSON.stringify(state)); }
  const answer = (cell) => state.answers[cell.id] || (state.answers[cell.id] = { rating: "", faults: [], note: "" });
  const rated = (cell) => Boolean(state.answers[cell.id] && state.answers[cell.id].rating);

  function el(tag, text, cls) {
    const e = document.createElement(tag);
    if (text !== undefined) e.textContent = text;
    if (cls) e.className = cls;
    return e;
  }

  function progress() {
    const n = S.cells.filter(rated).length;
    $("progress").textContent = n + " of " + S.cells.length + " rated";
    const strip = $("strip");
    S.cells.forEach((c, i) => {
      const b = strip.children[i];
      b.classList.toggle("done", rated(c));
      b.classList.toggle("now", i === state.current);
    });
  }

  function option(type, name, value, text, hint, checked, onchange) {
    const lab = el("label", undefined, "opt");
    const inp = document.createElement("input");
    inp.type = type; inp.name = name; inp.value = value; inp.checked = checked;
    inp.addEventListener("change", () => onchange(inp));
    lab.appendChild(inp);
    lab.appendChild(document.createTextNode(" " + text));
    if (hint) lab.appendChild(el("span", hint, "meta"));
    return lab;
  }

  function show(i) {
    state.current = Math.max(0, Math.min(S.cells.length - 1, i));
    save();
    const c = S.cells[state.current], a = answer(c);
    document.querySelector("aside").scrollTop = 0;
    $("cellhead").textContent = "Cell " + (state.current + 1) + " of " + S.cells.length + ": " + c.subject
      + ", task " + c.file + ", animation " + c.code;
    $("celldesc").textContent = "Rate the " + c.topic + " (Table " + c.table + ": " + c.title + ").";
    const frame = $("cell"), src = c.page + "#view=front";
    if (frame.getAttribute("src") !== src) frame.setAttribute("src", src);
    const scale = $("scale"); scale.replaceChildren(el("legend", "Rating"));
    S.scale.forEach((word, k) => {
      const n = S.negatives[word];
      const hint = "(" + n + (k === S.scale.length - 1 ? " or more" : "") + " negative" + (n === 1 ? "" : "s") + ")";
      scale.appendChild(option("radio", "rating", word, word, hint, a.rating === word, (inp) => {
        a.rating = inp.value; save(); progress();
      }));
    });
    const faults = $("faults"); faults.replaceChildren(el("legend", "Faults seen"));
    if (!c.faults.length) faults.appendChild(el("p", "The rubric lists no fault of this table for this task.", "meta"));
    c.faults.forEach((text) => {
      faults.appendChild(option("checkbox", "fault", text, text, "", a.faults.includes(text), (inp) => {
        a.faults = c.faults.filter((t) => t === inp.value ? inp.checked : a.faults.includes(t));
        save();
      }));
    });
    $("note").value = a.note;
    $("prev").disabled = state.current === 0;
    $("next").disabled = state.current === S.cells.length - 1;
    progress();
  }

  function field(x) {
    const s = String(x);
    return /[",\r\n]/.test(s) || s !== s.trim() ? '"' + s.replace(/"/g, '""') + '"' : s;
  }

  function csv() {
    const lines = [S.columns.join(",")];
    for (const c of S.cells) {
      if (!rated(c)) continue;
      const a = state.answers[c.id];
      const values = { subject: c.subject, task: c.file, version: c.code, table: c.table, component: "",
                       rating: a.rating, rater: state.rater.trim(), faults: a.faults.join(S.fault_separator),
                       note: a.note.trim(), session: S.session };
      lines.push(S.columns.map((k) => field(values[k])).join(","));
    }
    return lines.join("\n") + "\n";
  }

  function exportCsv() {
    const rater = state.rater.trim();
    if (!rater) { say("enter your name first: the export names its rater", true); $("rater").focus(); return false; }
    const n = S.cells.filter(rated).length;
    if (!n) { say("nothing rated yet", true); return false; }
    const a = document.createElement("a");
    a.href = URL.createObjectURL(new Blob([csv()], { type: "text/csv" }));
    a.download = "ratings-" + rater.replace(/[^A-Za-z0-9_-]+/g, "_") + "-" + S.session.slice(0, 8) + ".csv";
    document.body.appendChild(a); a.click(); a.remove();
    say("exported " + n + " rating" + (n === 1 ? "" : "s"));
    return true;
  }

  function start() {
    const strip = $("strip");
    S.cells.forEach((c, i) => {
      const b = el("button", String(i + 1));
      b.title = c.subject + ", task " + c.file + ", " + c.code + ", Table " + c.table;
      b.addEventListener("click", () => show(i));
      strip.appendChild(b);
    });
    $("rater").value = state.rater;
    $("rater").addEventListener("input", () => { state.rater = $("rater").value; save(); });
    $("note").addEventListener("input", () => { answer(S.cells[state.current]).note = $("note").value; save(); });
    $("prev").addEventListener("click", () => show(state.current - 1));
    $("next").addEventListener("click", () => show(state.current + 1));
    $("export").addEventListener("click", exportCsv);
    show(state.current || 0);
    say("ready"); status.dataset.ready = "1";
    window.cassiRate = { state: state, show: show, csv: csv };  // for tests and the console
  }

  if (!S) say("no session data (session.js did not load)", true);
  else start();
})();
