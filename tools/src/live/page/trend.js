// The trend of A6, A7 and the counts over the last minutes (uPlot): the history kept by the
// server (/api/units/N/trend, which also gives the step and the names), then a point from the
// events every step. The time axis reads the wall clock as hh:mm:ss (the PC's time of day),
// never a date.

import uPlot from "/vendor/uplot.mjs";
import { errorText } from "/dom.js";

const KEEP_S = 300;
const COLOURS = ["#5fb3ff", "#c792ea", "#ffb02e", "#3ddc84", "#ff5c5c", "#f07178", "#89ddff", "#c3e88d", "#ffcb6b", "#82aaff"];

export class Trend {
  constructor(addr) {
    this.addr = addr;
    this.root = document.createElement("div");
    this.root.className = "trend";
    this.t = [];
    this.names = [];
    this.series = [];
    this.last = 0;
    this.stepMs = null;
    this.plot = null;
    this.loaded = false;
    this.load();
  }

  async load() {
    try {
      const res = await fetch(`/api/units/${this.addr}/trend`);
      if (res.ok) {
        const h = await res.json();
        const now = Date.now() / 1000;
        this.stepMs = h.step_ms;
        this.names = h.names;
        this.t = h.t.map((s) => now + s);
        this.series = h.series.map((s) => s.slice());
      } else {
        this.root.textContent = `no trend: ${await errorText(res)}`;
      }
    } catch (e) {
      this.root.textContent = `no trend: the server did not answer (${e})`;
    }
    this.loaded = true;
    this.draw();
  }

  add(v) {
    const now = Date.now();
    if (!this.loaded || this.stepMs === null || now - this.last < this.stepMs || v.A6 === undefined) return;
    this.last = now;
    this.t.push(now / 1000);
    this.names.forEach((n, i) => this.series[i].push(v[n]));
    while (this.t.length && this.t[0] < now / 1000 - KEEP_S) {
      this.t.shift();
      this.series.forEach((s) => s.shift());
    }
    this.draw();
  }

  draw() {
    // Counters that never counted stay off the chart.
    const used = this.names.map((n, i) => i < 2 || this.series[i].some((x) => x > 0));
    const key = used.join();
    if (!this.plot || key !== this.key) {
      this.key = key;
      if (this.plot) this.plot.destroy();
      const series = [{ label: "time", value: (u, t) => (t == null ? "" : timeOfDay(t)) }];
      this.names.forEach((n, i) => {
        if (used[i]) series.push({ label: n, stroke: COLOURS[i], width: 1.5, scale: i < 2 ? "adc" : "count", points: { show: false } });
      });
      this.idx = this.names.map((n, i) => i).filter((i) => used[i]);
      this.plot = new uPlot({
        // A phone's width (390 px) leaves room for the card's and the group's edges.
        width: Math.max(200, Math.min(560, window.innerWidth - 90)),
        height: 150,
        series,
        scales: { x: { time: true }, adc: { range: [0, 1023] }, count: { auto: true } },
        axes: [
          { stroke: "#8b949e", grid: { stroke: "#30363d" }, space: 70, values: (u, ticks) => ticks.map(timeOfDay) },
          { scale: "adc", stroke: "#8b949e", grid: { stroke: "#30363d" }, size: 50 },
          { scale: "count", side: 1, stroke: "#8b949e", grid: { show: false }, size: 40 },
        ],
        legend: { live: false },
        cursor: { show: false },
      }, [this.t, ...this.idx.map((i) => this.series[i])], this.root);
      return;
    }
    this.plot.setData([this.t, ...this.idx.map((i) => this.series[i])]);
  }
}

// Seconds since 1970 as the PC's time of day, hh:mm:ss.
function timeOfDay(t) {
  const d = new Date(t * 1000);
  return [d.getHours(), d.getMinutes(), d.getSeconds()].map((n) => String(n).padStart(2, "0")).join(":");
}
