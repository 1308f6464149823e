// preform run report: draws the figures (plotly.js) as they come into view, sorts and filters
// the results table, opens a case a link points to. window.preformReport is for the tests.
(function () {
  "use strict";
  var report = (window.preformReport = { plotted: 0, ready: false });
  var hasPlotly = typeof window.Plotly !== "undefined";

  function draw(div) {
    if (!hasPlotly || div.dataset.drawn) return;
    div.dataset.drawn = "drawing";
    var spec = JSON.parse(document.getElementById(div.dataset.spec).textContent);
    var config = { responsive: true, displaylogo: false };
    window.Plotly.newPlot(div, spec.data, spec.layout, config).then(function () {
      div.dataset.drawn = "done";
      report.plotted += 1;
    });
  }
  // a closed case gives back its 3-D view's WebGL context: a browser keeps only about 16
  function release(div) {
    if (hasPlotly && div.dataset.drawn) {
      window.Plotly.purge(div);
      delete div.dataset.drawn;
    }
  }
  var observer = new IntersectionObserver(
    function (entries) {
      entries.forEach(function (e) { if (e.isIntersecting) draw(e.target); });
    },
    { rootMargin: "300px" }
  );
  document.querySelectorAll("div.plot").forEach(function (div) { observer.observe(div); });
  document.querySelectorAll("details.case").forEach(function (d) {
    d.addEventListener("toggle", function () {
      if (!d.open) d.querySelectorAll("div.plot").forEach(release);
    });
  });

  var table = document.getElementById("results");
  if (table) {
    var body = table.tBodies[0];
    var heads = Array.prototype.slice.call(table.tHead.rows[0].cells);
    var isNumber = function (s) { return s !== "" && !isNaN(Number(s)); };
    var key = function (row, col) {
      var cell = row.cells[col];
      return cell.dataset.key !== undefined ? cell.dataset.key : (cell.dataset.value || cell.textContent);
    };
    heads.forEach(function (th, col) {
      th.addEventListener("click", function () {
        var dir = th.dataset.sort === "asc" ? -1 : 1;
        heads.forEach(function (h) { delete h.dataset.sort; });
        th.dataset.sort = dir === 1 ? "asc" : "desc";
        var rows = Array.prototype.slice.call(body.rows);
        rows.sort(function (a, b) {
          var x = key(a, col), y = key(b, col);
          var c = isNumber(x) && isNumber(y) ? Number(x) - Number(y)
            : isNumber(x) ? -1 : isNumber(y) ? 1 : x.localeCompare(y);
          return c * dir;
        });
        rows.forEach(function (r) { body.appendChild(r); });
      });
    });
    var filter = document.getElementById("filter");
    var status = document.getElementById("status-filter");
    var apply = function () {
      var q = filter.value.toLowerCase();
      Array.prototype.forEach.call(body.rows, function (r) {
        r.hidden = !(r.textContent.toLowerCase().indexOf(q) >= 0 &&
                     (!status.value || r.dataset.status === status.value));
      });
    };
    filter.addEventListener("input", apply);
    status.addEventListener("change", apply);
  }

  function openTarget() {
    var el = location.hash ? document.getElementById(decodeURIComponent(location.hash.slice(1))) : null;
    if (el && el.tagName === "DETAILS") el.open = true;
  }
  window.addEventListener("hashchange", openTarget);
  openTarget();
  report.ready = true;
})();
