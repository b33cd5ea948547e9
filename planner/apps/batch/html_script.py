"""The script and style of ``report.html``'s task table and task panel
(:mod:`tooltransfer.planner.apps.batch.html_report`).

The table: a text filter (over every cell), one select per status, variant and tool, and sorting by
a click on a header (numbers by their values, text alphabetically; a second click reverses). The
matching rows are drawn a page at a time (the table's ``data-page`` rows; previous / next): rows
are hidden, never rebuilt, and only those whose state changes are touched, so filtering 4,000 rows is one pass over
precomputed texts and the layout of one page. ``window.ttShown`` holds the number of matching rows,
``window.ttDrawn`` those drawn, ``window.ttFilterMs`` the time of the last filtering pass (the layout
forced) [ms], measured by the browser test. A click on a row fills the task panel: the
scene of the Bokeh figure ``panel`` (sources ``panel_*``, lengths in mm) and the verdicts with their
full reasons.
"""

TABLE_CSS = """
.scroll { max-height: 38em; overflow-y: auto; border: 1px solid #ddd; }
#rows tbody tr { cursor: pointer; } #rows tbody tr:hover { background: #eef5ff; }
#rows tbody tr.selected { background: #dbeafe; }
#rows th { cursor: pointer; user-select: none; }
#rows { table-layout: fixed; }  /* fixed columns: a page's layout does not measure every cell */
#rows td { overflow: hidden; text-overflow: ellipsis; }
.filters { margin: 0.5em 0; } .filters label { margin-right: 1em; } #count { color: #555; }
#panel { min-width: 440px; max-width: 520px; }
"""

TABLE_JS = r"""
(function () {
  "use strict";
  var table = document.getElementById("rows");
  var tbody = table.tBodies[0];
  var rows = Array.prototype.slice.call(tbody.rows);
  var texts = rows.map(function (r) { return r.textContent.toLowerCase(); });
  var fields = ["status", "variant", "tool"];
  var tasks = JSON.parse(document.getElementById("tasks").textContent);
  var count = document.getElementById("count");

  var PAGE = parseInt(table.getAttribute("data-page"), 10);
  var page = 0;
  var matches = [];
  var drawn = rows.map(function (r) { return r.style.display !== "none"; });

  function draw() {
    var t0 = performance.now();
    var pages = Math.max(1, Math.ceil(matches.length / PAGE));
    page = Math.min(Math.max(page, 0), pages - 1);
    var on = new Set(matches.slice(page * PAGE, (page + 1) * PAGE));
    for (var i = 0; i < rows.length; i++) {
      var want = on.has(i);
      if (want !== drawn[i]) { rows[i].style.display = want ? "" : "none"; drawn[i] = want; }
    }
    count.textContent = matches.length + " of " + rows.length + " rows match; page " + (page + 1) + " of " + pages;
    void table.offsetHeight;  // the layout, inside the measured time
    window.ttShown = matches.length;
    window.ttDrawn = on.size;
    return performance.now() - t0;
  }

  function apply() {
    var t0 = performance.now();
    var q = document.getElementById("f-text").value.toLowerCase();
    var want = fields.map(function (f) { return document.getElementById("f-" + f).value; });
    matches = [];
    for (var i = 0; i < rows.length; i++) {
      var ok = (!q || texts[i].indexOf(q) >= 0);
      for (var k = 0; ok && k < fields.length; k++) {
        if (want[k] && rows[i].getAttribute("data-" + fields[k]) !== want[k]) { ok = false; }
      }
      if (ok) { matches.push(i); }
    }
    page = 0;
    draw();
    window.ttFilterMs = performance.now() - t0;
  }

  document.getElementById("prev").addEventListener("click", function () { page--; draw(); });
  document.getElementById("next").addEventListener("click", function () { page++; draw(); });
  document.getElementById("f-text").addEventListener("input", apply);
  fields.forEach(function (f) { document.getElementById("f-" + f).addEventListener("change", apply); });

  var order = {};
  Array.prototype.forEach.call(table.tHead.rows[0].cells, function (th, col) {
    th.addEventListener("click", function () {
      var dir = order[col] = -(order[col] || -1);
      var key = function (r) {
        var c = r.cells[col];
        var v = c.getAttribute("data-v");
        return v === null ? c.textContent : (v === "" ? Infinity : parseFloat(v));
      };
      var keyed = rows.map(function (r, i) { return [key(r), i, r]; });
      keyed.sort(function (a, b) {
        if (a[0] < b[0]) { return -dir; }
        if (a[0] > b[0]) { return dir; }
        return a[1] - b[1];
      });
      var frag = document.createDocumentFragment();
      keyed.forEach(function (k) { frag.appendChild(k[2]); });
      tbody.appendChild(frag);
      rows = keyed.map(function (k) { return k[2]; });
      texts = rows.map(function (r) { return r.textContent.toLowerCase(); });
      drawn = rows.map(function (r) { return r.style.display !== "none"; });
      apply();
    });
  });

  function source(name) {
    var doc = window.Bokeh && Bokeh.documents[0];
    return doc ? doc.get_model_by_name(name) : null;
  }

  function esc(s) {
    return String(s).replace(/[&<>"]/g, function (c) {
      return {"&": "&amp;", "<": "&lt;", ">": "&gt;", "\"": "&quot;"}[c];
    });
  }

  function show(id) {
    var t = tasks[id];
    if (!t || !source("panel_paths")) { return false; }
    var mm = function (v) { return v * 1000; };
    var discs = {x: [], y: [], r: []}, polys = {xs: [], ys: []};
    t.obs.forEach(function (o) {
      if (o.v) {
        polys.xs.push(o.v.map(function (p) { return mm(p[0]); }));
        polys.ys.push(o.v.map(function (p) { return mm(p[1]); }));
      } else { discs.x.push(mm(o.c[0])); discs.y.push(mm(o.c[1])); discs.r.push(mm(o.r)); }
    });
    var pucks = {x: [], y: [], r: [], c: [], what: []};
    [["start", t.start, "#444"], ["target", t.target, "#d62728"]].forEach(function (p) {
      if (p[1]) { pucks.x.push(mm(p[1][0])); pucks.y.push(mm(p[1][1])); pucks.r.push(mm(t.r));
                  pucks.c.push(p[2]); pucks.what.push(p[0]); }
    });
    var colours = JSON.parse(document.getElementById("colours").textContent);
    var paths = {xs: [], ys: [], c: [], variant: [], status: []};
    var html = "<table class=\"data\"><tr><th class=\"text\">variant</th><th class=\"text\">status</th>" +
               "<th class=\"text\">reason</th></tr>";
    Object.keys(t.v).sort().forEach(function (v) {
      var e = t.v[v];
      if (e.path[0].length) {
        paths.xs.push(e.path[0].map(mm)); paths.ys.push(e.path[1].map(mm));
        paths.c.push(colours[v] || "#000"); paths.variant.push(v); paths.status.push(e.status);
      }
      html += "<tr><td class=\"text\">" + esc(v) + "</td><td class=\"text s-" + esc(e.status) + "\">" +
              esc(e.status) + "</td><td class=\"reason\">" + esc(e.reason) + "</td></tr>";
    });
    source("panel_discs").data = discs;
    source("panel_polys").data = polys;
    source("panel_pucks").data = pucks;
    source("panel_paths").data = paths;
    document.getElementById("panel-title").textContent = "task " + id;
    document.getElementById("panel-text").innerHTML = html + "</table>";
    window.ttPanelTask = id;
    return true;
  }
  window.ttShowTask = show;

  tbody.addEventListener("click", function (ev) {
    var tr = ev.target.closest("tr");
    if (!tr) { return; }
    rows.forEach(function (r) { r.classList.remove("selected"); });
    tr.classList.add("selected");
    show(tr.getAttribute("data-task"));
  });

  apply();
  var tries = 0;
  (function first() {  // the first task once Bokeh has built the document
    if (rows.length && !show(rows[0].getAttribute("data-task")) && tries++ < 200) { setTimeout(first, 25); }
  })();
})();
"""
