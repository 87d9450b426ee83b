// The dashboard's only script: sortable tables, the plotly charts of a building page, and a
// poll that reloads the page when a running job ends. No inline script (the CSP forbids it).
"use strict";

function sortTable(table, column, type) {
  const body = table.tBodies[0];
  const rows = Array.from(body.rows);
  const ascending = table.dataset.sortColumn === String(column) ? table.dataset.sortDir !== "asc" : true;
  const key = (row) => {
    const cell = row.cells[column];
    const raw = cell.dataset.sort !== undefined ? cell.dataset.sort : cell.textContent.trim();
    return type === "number" ? parseFloat(raw) : raw.toLowerCase();
  };
  rows.sort((a, b) => {
    const x = key(a), y = key(b);
    const order = x < y ? -1 : x > y ? 1 : 0;
    return ascending ? order : -order;
  });
  rows.forEach((row) => body.appendChild(row));
  table.dataset.sortColumn = String(column);
  table.dataset.sortDir = ascending ? "asc" : "desc";
  table.querySelectorAll("th").forEach((th, i) => {
    th.setAttribute("aria-sort", i === column ? (ascending ? "ascending" : "descending") : "none");
  });
}

function makeSortable() {
  document.querySelectorAll("table.sortable").forEach((table) => {
    table.querySelectorAll("thead th").forEach((th, column) => {
      th.tabIndex = 0;
      const sort = () => sortTable(table, column, th.dataset.type || "text");
      th.addEventListener("click", sort);
      th.addEventListener("keydown", (e) => { if (e.key === "Enter") sort(); });
    });
  });
}

const LAYOUT = {
  margin: { l: 56, r: 56, t: 16, b: 40 },
  hovermode: "x unified",
  legend: { orientation: "h", y: -0.18 },
  xaxis: { type: "date" },
  yaxis: { title: { text: "°C" } },
};
const CONFIG = { responsive: true, displaylogo: false, scrollZoom: true };

function forecastTraces(series) {
  const traces = [
    { name: "measured t_in", x: series.measured.x, y: series.measured.y, mode: "lines", line: { color: "#222" } },
    { name: "model (open loop)", x: series.predicted.x, y: series.predicted.y, mode: "lines", line: { color: "#1f77b4", dash: "dot" } },
  ];
  const f = series.forecast;
  if (f) {
    const upper = f.y.map((y, i) => y + 2 * f.std[i]);
    const lower = f.y.map((y, i) => y - 2 * f.std[i]);
    traces.push(
      { name: "+2σ", x: f.x, y: upper, mode: "lines", line: { width: 0 }, showlegend: false, hoverinfo: "skip" },
      { name: "forecast ±2σ", x: f.x, y: lower, mode: "lines", line: { width: 0 }, fill: "tonexty", fillcolor: "rgba(214,39,40,0.15)", hoverinfo: "skip" },
      { name: "forecast", x: f.x, y: f.y, mode: "lines", line: { color: "#d62728" } },
    );
  }
  return traces;
}

function dataTraces(series) {
  return [
    { name: "t_in", x: series.x, y: series.t_in, mode: "lines", line: { color: "#222" } },
    { name: "t_out", x: series.x, y: series.t_out, mode: "lines", line: { color: "#2ca02c" } },
    { name: "q_hvac", x: series.x, y: series.q_hvac, mode: "lines", yaxis: "y2", line: { color: "#ff7f0e", width: 1 } },
  ];
}

function drawCharts() {
  const source = document.getElementById("chart-json");
  if (!source || typeof Plotly === "undefined") return;
  const charts = JSON.parse(source.textContent);
  const forecast = document.getElementById("chart-forecast");
  Plotly.newPlot(forecast, forecastTraces(charts.forecast), LAYOUT, CONFIG);
  const data = document.getElementById("chart-data");
  const layout = { ...LAYOUT, yaxis2: { title: { text: "q_hvac [W]" }, overlaying: "y", side: "right", showgrid: false } };
  Plotly.newPlot(data, dataTraces(charts.data), layout, CONFIG);
  document.body.dataset.charts = "drawn";
}

function pollJobs() {
  const script = document.getElementById("dashboard-script");
  if (!script || script.dataset.active !== "true") return;
  const url = "/ui/buildings/" + script.dataset.building + "/jobs";
  const tick = () => {
    fetch(url, { credentials: "same-origin", cache: "no-store" })
      .then((r) => (r.ok ? r.json() : Promise.reject(r.status)))
      .then((body) => { if (body.active.length === 0) window.location.reload(); else setTimeout(tick, 1000); })
      .catch(() => setTimeout(tick, 5000));
  };
  setTimeout(tick, 1000);
}

document.addEventListener("DOMContentLoaded", () => {
  makeSortable();
  drawCharts();
  pollJobs();
});
