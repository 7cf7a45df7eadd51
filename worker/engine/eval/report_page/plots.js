// Small SVG line plots (linear or log axes) for the report: a few axes, lines and markers need no
// plotting library. EndoPlots.linePlot(options) returns a <figure>.
"use strict";
const EndoPlots = (() => {
  const SVG = "http://www.w3.org/2000/svg";
  const COLOURS = ["#1f6feb", "#c2410c", "#15803d", "#7c3aed", "#0e7490"];

  function el(name, attributes, parent) {
    const node = document.createElementNS(SVG, name);
    for (const [key, value] of Object.entries(attributes || {})) node.setAttribute(key, value);
    if (parent) parent.appendChild(node);
    return node;
  }

  // Ticks at 1-2-5 multiples of a power of ten, about `count` of them over [lo, hi].
  function linearTicks(lo, hi, count) {
    const raw = (hi - lo) / Math.max(1, count);
    const power = Math.pow(10, Math.floor(Math.log10(raw)));
    const step = [1, 2, 5, 10].map((m) => m * power).find((s) => s >= raw) || raw;
    const ticks = [];
    for (let t = Math.ceil(lo / step - 1e-9) * step; t <= hi + step * 1e-9; t += step) ticks.push(t);
    return { ticks, step };
  }

  function tickLabel(value, step) {
    if (value === 0) return "0";
    const digits = Math.max(0, -Math.floor(Math.log10(step) + 1e-9));
    return value.toFixed(Math.min(digits, 6));
  }

  // A value as a tooltip shows it: four significant digits, not the float's seventeen.
  function shortNumber(value) {
    return Number.isInteger(value) ? String(value) : String(Number(value.toPrecision(4)));
  }

  // A marker's fill and outline: hollow (reduced renders) or filled in the series' colour.
  function markerStyle(s, colour) {
    return s.hollow ? {fill: '#fff', stroke: colour, 'stroke-width': 1.5} : {fill: colour};
  }

  // [lo, hi] widened to whole decades, for a log axis.
  function decades(lo, hi) {
    lo = Math.pow(10, Math.floor(Math.log10(lo)));
    hi = Math.pow(10, Math.ceil(Math.log10(hi)));
    return [lo, hi > lo ? hi : lo * 10];
  }

  function extent(values) {
    let lo = Infinity, hi = -Infinity;
    for (const v of values) if (Number.isFinite(v)) { lo = Math.min(lo, v); hi = Math.max(hi, v); }
    return [lo, hi];
  }

  function linePlot(options) {
    const width = options.width || 460, height = options.height || 280;
    const margin = { left: 58, right: 14, top: 44, bottom: 42 };
    // The legend runs along the top margin, one entry per series, in as many rows as their labels need
    // (about 6.5 px a character at 11 px), clear of the data.
    const legend = [];
    {
      let x = margin.left, row = 0;
      for (const s of options.series.filter((entry) => entry.x.length > 0)) {
        const entryWidth = 27 + 6.5 * s.label.length + 16;
        if (x > margin.left && x + entryWidth > width - margin.right) {
          x = margin.left;
          ++row;
        }
        legend.push({x, y: 32 + 14 * row});
        x += entryWidth;
      }
      margin.top += 14 * row;
    }
    const figure = document.createElement("figure");
    figure.className = "plot";
    const svg = el("svg", { width, height, viewBox: `0 0 ${width} ${height}`, role: "img" }, figure);
    el("title", {}, svg).textContent = options.title || "";
    const series = options.series.filter((s) => s.x.length > 0);
    const usable = (x) => Number.isFinite(x) && (!options.xLog || x > 0);
    const usableY = (y) => Number.isFinite(y) && (!options.yLog || y > 0);
    const xs = [], ys = [];
    for (const s of series) {
      s.x.forEach((x, i) => {
        if (usable(x) && usableY(s.y[i])) {
          xs.push(x);
          ys.push(s.y[i]);
        }
      });
    }
    const text = (x, y, content, attributes) => {
      const node = el("text", Object.assign({ x, y, "font-size": 11, fill: "#5b6475" }, attributes), svg);
      node.textContent = content;
      return node;
    };
    text(margin.left, 16, options.title || "", { "font-size": 13, fill: "#1d2330", "font-weight": 600 });
    if (xs.length === 0) {
      text(width / 2, height / 2, "no data", { "text-anchor": "middle" });
      return figure;
    }
    let [x0, x1] = extent(xs);
    let [y0, y1] = options.yRange || extent(ys);
    if (options.xLog) {
      [x0, x1] = decades(x0, x1);
    } else if (x1 <= x0) {
      x1 = x0 + 1;
    }
    if (options.yLog) {
      [y0, y1] = decades(y0, y1);
    } else {
      if (y1 <= y0) {
        y0 -= 0.5;
        y1 += 0.5;
      }
      const pad = (y1 - y0) * 0.06;
      if (!options.yRange) {
        y0 -= pad;
        y1 += pad;
      }
    }
    const plotW = width - margin.left - margin.right, plotH = height - margin.top - margin.bottom;
    const px = options.xLog
      ? (x) => margin.left + (Math.log10(x) - Math.log10(x0)) / (Math.log10(x1) - Math.log10(x0)) * plotW
      : (x) => margin.left + (x - x0) / (x1 - x0) * plotW;
    const py = options.yLog ? (y) => margin.top +
            (1 - (Math.log10(y) - Math.log10(y0)) / (Math.log10(y1) - Math.log10(y0))) * plotH :
                              (y) => margin.top + (1 - (y - y0) / (y1 - y0)) * plotH;
    el("rect", { x: margin.left, y: margin.top, width: plotW, height: plotH, fill: "none", stroke: "#d9dde5" }, svg);

    if (options.yLog) {
      for (let decade = Math.log10(y0); decade <= Math.log10(y1) + 1e-9; ++decade) {
        const value = Math.pow(10, decade);
        el('line',
           {x1: margin.left, x2: margin.left + plotW, y1: py(value), y2: py(value), stroke: '#eef0f4'}, svg);
        text(margin.left - 6, py(value) + 4, tickLabel(value, value), {'text-anchor': 'end'});
        for (let m = 2; m <= 9 && value * m < y1; ++m) {
          const y = py(value * m);
          el('line', {x1: margin.left, x2: margin.left + 4, y1: y, y2: y, stroke: '#9aa3b2'}, svg);
          if (m === 2 || m === 5)
            text(margin.left - 6, y + 4, tickLabel(value * m, value), {'text-anchor': 'end'});
        }
      }
    } else {
      const yTicks = linearTicks(y0, y1, 5);
      for (const t of yTicks.ticks) {
        el('line', {x1: margin.left, x2: margin.left + plotW, y1: py(t), y2: py(t), stroke: '#eef0f4'}, svg);
        text(margin.left - 6, py(t) + 4, tickLabel(t, yTicks.step), {'text-anchor': 'end'});
      }
    }
    if (options.xLog) {
      for (let decade = Math.log10(x0); decade <= Math.log10(x1) + 1e-9; ++decade) {
        const value = Math.pow(10, decade);
        el("line", { x1: px(value), x2: px(value), y1: margin.top, y2: margin.top + plotH, stroke: "#eef0f4" }, svg);
        text(px(value), margin.top + plotH + 15, tickLabel(value, value), { "text-anchor": "middle" });
        for (let m = 2; m <= 9 && value * m < x1; ++m) {
          const x = px(value * m);
          el("line", { x1: x, x2: x, y1: margin.top + plotH, y2: margin.top + plotH - 4, stroke: "#9aa3b2" }, svg);
        }
      }
    } else {
      const xTicks = linearTicks(x0, x1, 6);
      for (const t of xTicks.ticks) {
        el("line", { x1: px(t), x2: px(t), y1: margin.top, y2: margin.top + plotH, stroke: "#eef0f4" }, svg);
        text(px(t), margin.top + plotH + 15, tickLabel(t, xTicks.step), { "text-anchor": "middle" });
      }
    }
    text(margin.left + plotW / 2, height - 6, options.xLabel || "", { "text-anchor": "middle" });
    text(14, margin.top + plotH / 2, options.yLabel || "",
         { "text-anchor": "middle", transform: `rotate(-90 14 ${margin.top + plotH / 2})` });

    series.forEach((s, index) => {
      const colour = s.colour || COLOURS[index % COLOURS.length];
      if (!s.markersOnly) {
        let path = "", pen = false;
        s.x.forEach((x, i) => {
          const ok = usable(x) && usableY(s.y[i]);
          if (ok) path += `${pen ? "L" : "M"}${px(x).toFixed(1)},${py(s.y[i]).toFixed(1)}`;
          pen = ok;
        });
        el("path", Object.assign({ d: path, fill: "none", stroke: colour, "stroke-width": 1.8 },
                                 s.dashed ? { "stroke-dasharray": "5 4" } : {}), svg);
      }
      s.x.forEach((x, i) => {
        if (!usable(x) || !usableY(s.y[i])) return;
        const dot =
            el('circle',
               Object.assign({cx: px(x), cy: py(s.y[i]), r: s.markersOnly ? 3 : 2.2}, markerStyle(s, colour)),
               svg);
        el('title', {}, dot).textContent =
            `${s.label}: ${shortNumber(s.y[i])} at ${options.xName || 'x'} ${shortNumber(x)}`;
      });
      const lx = legend[index].x, ly = legend[index].y;
      if (s.markersOnly) {
        el('circle', Object.assign({cx: lx + 11, cy: ly - 4, r: 3}, markerStyle(s, colour)), svg);
      } else {
        el("line", Object.assign({ x1: lx, x2: lx + 22, y1: ly - 4, y2: ly - 4, stroke: colour, "stroke-width": 2 },
                                 s.dashed ? { "stroke-dasharray": "5 4" } : {}), svg);
      }
      text(lx + 27, ly, s.label, { fill: "#1d2330" });
    });
    if (options.caption) {
      const caption = document.createElement("figcaption");
      caption.textContent = options.caption;
      figure.appendChild(caption);
    }
    return figure;
  }

  return { linePlot };
})();
