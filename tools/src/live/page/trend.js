// The trend of A6, A7 and the counts over the last minutes (uPlot): the history kept by the
// server (/api/units/N/trend), then a point from the events every quarter second.

import uPlot from "/vendor/uplot.mjs";

const STEP_MS = 250;
const KEEP_S = 300;
const NAMES = ["A6", "A7", "C0", "C1", "C2", "C3", "C4", "C5", "C6", "C7"];
const COLOURS = ["#5fb3ff", "#c792ea", "#ffb02e", "#3ddc84", "#ff5c5c", "#f07178", "#89ddff", "#c3e88d", "#ffcb6b", "#82aaff"];

export class Trend {
  constructor(addr) {
    this.addr = addr;
    this.root = document.createElement("div");
    this.root.className = "trend";
    this.t = [];
    this.series = NAMES.map(() => []);
    this.last = 0;
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
        this.t = h.t.map((s) => now + s);
        this.series = h.series.map((s) => s.slice());
      }
    } catch (e) {
      // No history: the trend starts now.
    }
    this.loaded = true;
    this.draw();
  }

  add(v) {
    const now = Date.now();
    if (!this.loaded || now - this.last < STEP_MS || v.A6 === undefined) return;
    this.last = now;
    this.t.push(now / 1000);
    NAMES.forEach((n, i) => this.series[i].push(v[n]));
    while (this.t.length && this.t[0] < now / 1000 - KEEP_S) {
      this.t.shift();
      this.series.forEach((s) => s.shift());
    }
    this.draw();
  }

  draw() {
    // Counters that never counted stay off the chart.
    const used = NAMES.map((n, i) => i < 2 || this.series[i].some((x) => x > 0));
    const key = used.join();
    if (!this.plot || key !== this.key) {
      this.key = key;
      if (this.plot) this.plot.destroy();
      const series = [{}];
      NAMES.forEach((n, i) => {
        if (used[i]) series.push({ label: n, stroke: COLOURS[i], width: 1.5, scale: i < 2 ? "adc" : "count", points: { show: false } });
      });
      this.idx = NAMES.map((n, i) => i).filter((i) => used[i]);
      this.plot = new uPlot({
        width: 530,
        height: 150,
        series,
        scales: { x: { time: true }, adc: { range: [0, 1023] }, count: { auto: true } },
        axes: [
          { stroke: "#8b949e", grid: { stroke: "#30363d" } },
          { scale: "adc", stroke: "#8b949e", grid: { stroke: "#30363d" }, size: 50 },
          { scale: "count", side: 1, stroke: "#8b949e", grid: { show: false }, size: 40 },
        ],
        legend: { live: false },
      }, [this.t, ...this.idx.map((i) => this.series[i])], this.root);
      return;
    }
    this.plot.setData([this.t, ...this.idx.map((i) => this.series[i])]);
  }
}
