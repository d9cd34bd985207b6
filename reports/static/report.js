// The report's pages: long tables drawn when their <details> is first opened (index and
// subject pages), and a subject page's filters of its fault cards and links that open a folded
// group (a classic script: the pages open from file://, where modules and fetch() are blocked).
(function () {
  "use strict";
  function td(row, text) { var c = row.insertCell(-1); c.textContent = text; }
  document.querySelectorAll("script.lazy-rows").forEach(function (data) {
    var d = data.closest("details");
    function draw() {
      if (!d.open || d.dataset.drawn) return;
      d.dataset.drawn = "1";
      var x = JSON.parse(data.textContent), table = d.querySelector("table");
      x.rows.forEach(function (r) {
        var row = table.insertRow(-1);
        if (!x.checks) { r.forEach(function (v) { td(row, v); }); return; }
        // a silent-check row: task, check (by number), value, threshold
        var c = x.checks[r[1]];
        td(row, r[0]); td(row, c[0]); td(row, c[1]); td(row, r[2] + " " + c[2]); td(row, r[3]);
        td(row, c[3]);
      });
      var note = d.querySelector(".lazy-note");
      if (note) note.hidden = true;
    }
    d.addEventListener("toggle", draw);
    draw();
  });
  var form = document.getElementById("filter");
  if (!form) return;
  var shown = document.getElementById("shown");
  var cards = Array.prototype.slice.call(document.querySelectorAll("div.fired"));
  var groups = Array.prototype.slice.call(document.querySelectorAll("details.check"));
  var opened = groups.map(function (g) { return g.open; });  // the page's own choice
  form.hidden = false;
  function apply() {
    var el = form.elements;
    var f = {version: el.version.value, table: el.table.value, check: el.check.value,
             task: el.task.value.trim()};
    var active = f.version || f.table || f.check || f.task, n = 0;
    groups.forEach(function (g, i) {
      var sec = g.closest("section.table"), ver = g.closest("section.version");
      var on = (!f.version || ver.dataset.version === f.version)
        && (!f.table || sec.dataset.table === f.table) && (!f.check || g.dataset.check === f.check);
      var any = 0;
      g.querySelectorAll("div.fired").forEach(function (c) {
        var yes = on && (!f.task || c.dataset.task === f.task);
        c.hidden = !yes; any += yes;
      });
      g.hidden = !any; n += any;
      g.open = active ? any > 0 : opened[i];
    });
    document.querySelectorAll("section.table, section.version").forEach(function (sec) {
      sec.hidden = !!active && !sec.querySelector("details.check:not([hidden])");
    });
    shown.textContent = active ? n + " of " + cards.length + " fault cards shown" : cards.length + " fault cards";
  }
  form.addEventListener("input", apply);
  form.addEventListener("reset", function () { setTimeout(apply, 0); });
  form.addEventListener("submit", function (e) { e.preventDefault(); });
  form.querySelectorAll("button[data-open]").forEach(function (b) {
    b.addEventListener("click", function () {
      groups.forEach(function (g) { if (!g.hidden) g.open = b.dataset.open === "1"; });
    });
  });
  // a link to a folded group, or to a card or section the filter hides, shows it
  function reveal() {
    var id = decodeURIComponent(location.hash.slice(1)), el = id && document.getElementById(id);
    if (!el) return;
    if (el.closest("[hidden]")) { form.reset(); apply(); }
    if (el.tagName === "DETAILS") el.open = true;
    for (var p = el.parentElement; p; p = p.parentElement) if (p.tagName === "DETAILS") p.open = true;
    el.scrollIntoView();
  }
  window.addEventListener("hashchange", reveal);
  apply();
  reveal();
})();
