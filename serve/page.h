// The monitoring page pyrocam-serve serves at /: one panel per server (this one, those given with
// --server, or ?servers=host:port,host:port), each with the live image, the statistics, a
// temperature-over-time plot (Chart.js) and the alarm state, fed by the server's /events.
#pragma once

namespace pyrocam::serve {

// host:port (a name, an IPv4 address or a bracketed IPv6 one), in the ECMAScript syntax both
// std::regex and the page's JavaScript read: the server checks --server with it, the page the
// names it is given (anything else is left out).
#define PYROCAM_SERVE_HOST_PORT R"(^([A-Za-z0-9.-]+|\[[0-9A-Fa-f:.]+\])(:[0-9]{1,5})?$)"

inline constexpr const char* kPage = R"PAGE(<!DOCTYPE html>
<html lang="en">
<head>
<meta charset="utf-8">
<title>pyrocam monitor</title>
<meta name="viewport" content="width=device-width, initial-scale=1">
<style>
  body { font-family: sans-serif; background: #1b1d21; color: #e8e8e8; margin: 0; }
  header { padding: 8px 16px; background: #2a2d33; font-size: 18px; }
  main { display: flex; flex-wrap: wrap; gap: 16px; padding: 16px; }
  .panel { background: #25282d; border-radius: 6px; padding: 12px; width: 640px; }
  .panel h2 { font-size: 16px; margin: 0 0 8px 0; display: flex; justify-content: space-between; }
  .panel img { width: 100%; image-rendering: pixelated; background: #000; min-height: 120px; }
  table { width: 100%; border-collapse: collapse; margin: 8px 0; }
  td { padding: 2px 6px; border-bottom: 1px solid #333; }
  td.v { text-align: right; font-variant-numeric: tabular-nums; font-weight: bold; }
  .badge { padding: 2px 8px; border-radius: 4px; font-size: 13px; }
  .ok { background: #2e6b3a; } .lost { background: #7a5a12; } .raised { background: #b3261e; }
  .off { background: #444; }
  .log { font-size: 12px; max-height: 90px; overflow-y: auto; color: #bbb; }
  canvas { background: #202226; }
</style>
</head>
<body>
<header>pyrocam monitor <span id="summary" style="font-size:13px;color:#aaa"></span></header>
<main id="panels"></main>
<script src="/chart.js"></script>
<script>
"use strict";
const fmt = (v, d = 1) => (typeof v === "number" ? v.toFixed(d) : "–");
const query = new URLSearchParams(location.search);
const maxPoints = 300;

const isHostPort = (s) => /)PAGE" PYROCAM_SERVE_HOST_PORT R"PAGE(/.test(s);

function makePanel(index, server) {
  const base = server ? "http://" + server : "";
  const el = document.createElement("section");
  el.className = "panel";
  el.innerHTML = `
    <h2><span id="name-${index}"></span>
      <span><span class="badge lost" id="camera-${index}">connecting</span>
      <span class="badge off" id="alarm-${index}">no alarm set</span></span></h2>
    <img id="frame-${index}" alt="live image">
    <table>
      <tr><td id="median-label-${index}">median</td><td class="v" id="median-${index}">–</td>
          <td>peak</td><td class="v" id="peak-${index}">–</td></tr>
      <tr><td>min / max</td><td class="v" id="minmax-${index}">–</td>
          <td id="peak-at-label-${index}">peak at (x, y)</td><td class="v" id="peak-at-${index}">–</td></tr>
      <tr><td>valid pixels</td><td class="v" id="valid-${index}">–</td>
          <td>frame time</td><td class="v" id="time-${index}">–</td></tr>
      <tr><td>updates</td><td class="v" id="updates-${index}">0</td>
          <td>estimator</td><td class="v" id="method-${index}">–</td></tr>
    </table>
    <div style="position: relative; height: 200px"><canvas id="chart-${index}"></canvas></div>
    <div class="log" id="log-${index}"></div>`;
  document.getElementById("panels").appendChild(el);
  const $ = (id) => document.getElementById(id + "-" + index);
  // The name as text and the address as a property: a link's ?servers= never becomes markup.
  $("name").textContent = server || location.host;
  $("frame").src = base + "/stream.mjpg";
  let chart = null;
  if (window.Chart) {
    chart = new Chart($("chart").getContext("2d"), {
      type: "line",
      data: { labels: [], datasets: [
        { label: "median °C", data: [], borderColor: "#4fc3f7", pointRadius: 0, borderWidth: 2 },
        { label: "peak °C", data: [], borderColor: "#ff7043", pointRadius: 0, borderWidth: 2 },
        { label: "alarm threshold °C", data: [], borderColor: "#e53935", borderDash: [6, 4],
          pointRadius: 0, borderWidth: 1 } ] },
      options: { animation: false, responsive: true, maintainAspectRatio: false,
        scales: { x: { ticks: { color: "#aaa", maxTicksLimit: 8 } },
                  y: { ticks: { color: "#aaa" }, title: { display: true, text: "°C", color: "#aaa" } } },
        plugins: { legend: { labels: { color: "#ddd" } } } } });
  } else {
    $("chart").replaceWith(Object.assign(document.createElement("p"),
      { textContent: "No plot: Chart.js did not load (install libjs-chart.js on the server)." }));
  }
  let updates = 0, threshold = null, outputPixel = 1;  // sensor pixels a reading spans, a side

  function log(text) {
    const line = document.createElement("div");
    line.textContent = new Date().toLocaleTimeString() + "  " + text;
    $("log").prepend(line);
  }
  function showStats(s) {
    const r = s["region-median-c"] !== undefined || s["region-x"] !== undefined ? "region-" : "";
    $("median-label").textContent = r ? "region median" : "median";
    $("median").textContent = fmt(s[r + "median-c"]) + " °C";
    // Pixels too bright to read: the peak read beside them is only a lower bound.
    // Pixels hotter than the model's range likewise.
    const saturated = s[r + "saturated"] ?? 0, above = s[r + "above-range"] ?? 0;
    // A lower bound has no interval; a reading has the expanded systematic one of the model.
    const sys = saturated > 0 || above > 0 ? undefined : s[r + "peak-u-sys-c"];
    $("peak").textContent = (saturated > 0 || above > 0 ? "≥ " : "") + fmt(s[r + "peak-c"]) + " °C" +
      (sys !== undefined ? ` ± ${fmt(sys, 0)} sys.` : "") +
      (saturated > 0 ? ` (${saturated} px saturated)` : "") +
      (above > 0 ? ` (${above} px above the model's range)` : "");
    // In sensor pixels: a 5x5 camera's readings are per macro-pixel, the peak at its centre.
    const at = (v) => v * outputPixel + (outputPixel - 1) / 2;
    $("peak-at-label").textContent = outputPixel > 1 ? "peak at (x, y), sensor px" : "peak at (x, y)";
    $("peak-at").textContent = s[r + "peak-x"] !== undefined ? `${at(s[r + "peak-x"])}, ${at(s[r + "peak-y"])}` : "–";
    $("minmax").textContent = fmt(s[r + "min-c"], 0) + " / " + fmt(s[r + "max-c"], 0);
    $("valid").textContent = fmt(100 * (s[r + "valid-fraction"] ?? NaN), 1) + " %";
    $("time").textContent = s.timestamp != null ? fmt(s.timestamp / 1e9, 2) + " s" : "–";
    $("method").textContent = s.method || "–";
    $("updates").textContent = String(++updates);
    if (chart) {
      const d = chart.data;
      d.labels.push(new Date().toLocaleTimeString());
      d.datasets[0].data.push(s[r + "median-c"] ?? null);
      d.datasets[1].data.push(s[r + "peak-c"] ?? null);
      d.datasets[2].data.push(threshold);
      if (d.labels.length > maxPoints) { d.labels.shift(); d.datasets.forEach((x) => x.data.shift()); }
      chart.update("none");
    }
  }
  const alarmLine = (a) => a.why ? `alarm ${a.state}: ${a.why}`
                                 : `alarm ${a.state}: ${a.statistic} ${fmt(a["value-c"])} °C`;
  function showAlarm(a, quiet) {
    threshold = a["threshold-c"] ?? null;
    const raised = a.state === "raised";
    $("alarm").className = "badge " + (raised ? "raised" : "ok");
    $("alarm").textContent = raised ? `ALARM ${a.statistic} ${fmt(a["value-c"])} °C` +
                                        (a.saturated ? " and saturated" : "") + ` > ${fmt(a["threshold-c"])}`
                                    : `alarm clear (< ${fmt(a["threshold-c"])} °C)`;
    if (!quiet) log(alarmLine(a));
  }
  function showWarning(w) {
    log("warning: " + (w.message.startsWith(w.source + ":") ? "" : w.source + ": ") + w.message);
  }
  function showCamera(c) {
    $("camera").className = "badge " + (c.state === "running" ? "ok" : "lost");
    $("camera").textContent = c.state === "running" ? "camera running" : "camera lost";
    if (c.state !== "running") log("camera lost: " + (c.why || ""));
    // The last image stays in view but faded: it is not the camera's now.
    $("frame").style.opacity = c.state === "running" ? "" : "0.35";
  }
  // The image's size once a frame came (tests read it from the DOM).
  setInterval(() => { $("frame").dataset.width = String($("frame").naturalWidth); }, 250);
  const events = new EventSource(base + "/events");
  // Every connection starts with a hello, a reconnection too: the log and the other servers'
  // panels only from the first (a second copy of each panel shared the first one's ids).
  let greeted = false;
  events.addEventListener("hello", (e) => {
    const s = JSON.parse(e.data);
    if (Number.isInteger(s["output-pixel"]) && s["output-pixel"] > 0) outputPixel = s["output-pixel"];
    if (s.stats) showStats(s.stats);
    if (s.camera) showCamera(s.camera);
    if (!greeted) {
      (s["alarm-log"] || []).forEach((a) => log(alarmLine(a)));
      if (s.warning) showWarning(s.warning);
      if (index === 0 && !query.has("servers"))
        (s.servers || []).filter(isHostPort).forEach((other, i) => makePanel(i + 1, other));
    } else {
      log("reconnected to the server");
    }
    if (s.alarm) showAlarm(s.alarm, true);
    greeted = true;
  });
  events.addEventListener("stats", (e) => showStats(JSON.parse(e.data)));
  events.addEventListener("alarm", (e) => showAlarm(JSON.parse(e.data), false));
  events.addEventListener("camera", (e) => showCamera(JSON.parse(e.data)));
  events.addEventListener("warning", (e) => showWarning(JSON.parse(e.data)));
  events.onerror = () => {
    $("camera").className = "badge lost";
    $("camera").textContent = "server unreachable";
    $("frame").style.opacity = "0.35";
  };
}

const servers = query.has("servers") ? query.get("servers").split(",").filter(isHostPort) : [""];
servers.forEach((s, i) => makePanel(i, s));
document.getElementById("summary").textContent = servers.length > 1 ? servers.length + " servers" : "";
</script>
</body>
</html>
)PAGE";

}  // namespace pyrocam::serve
