// Builds the report from the one data block (eval::WriteReport): the frame viewer, the 3D surface,
// the plots and tables. Every number taken from metrics.json is shown by metricSpan, which records its
// JSON pointer (data-metric), so a reader (and the browser test) can trace each number to its source.
"use strict";
(() => {
  const data = JSON.parse(document.getElementById("report-data").textContent);
  const metrics = data.metrics || {};
  const $ = (id) => document.getElementById(id);

  function node(tag, attributes, children) {
    const element = document.createElement(tag);
    for (const [key, value] of Object.entries(attributes || {})) {
      if (key === "class") element.className = value;
      else if (key === "text") element.textContent = value;
      else element.setAttribute(key, value);
    }
    for (const child of children || []) {
      element.appendChild(typeof child === "string" ? document.createTextNode(child) : child);
    }
    return element;
  }

  function lookup(root, pointer) {
    let value = root;
    for (const part of pointer.split("/").slice(1)) {
      if (value === null || value === undefined) return undefined;
      value = value[part.replace(/~1/g, "/").replace(/~0/g, "~")];
    }
    return value;
  }

  // A number of metrics.json (or config.json with source "config"): `digits` decimals, or with
  // `precision` that many significant digits; `factor` scales it for display (e.g. 100 for %).
  function metricSpan(pointer, format, source) {
    const f = Object.assign({ digits: 2, factor: 1 }, format || {});
    const value = lookup(
        source === 'config'     ? data.config :
            source === 'render' ? data.render :
                                  metrics,
        pointer);
    const attributes = {
      [source === 'config'     ? 'data-config' :
           source === 'render' ? 'data-render' :
                                 'data-metric']: pointer
    };
    if (f.factor !== 1) attributes["data-factor"] = f.factor;
    let text = "\u2014";
    if (typeof value === "number") {
      const shown = value * f.factor;
      if (f.precision) {
        attributes["data-precision"] = f.precision;
        const tiny = shown !== 0 && (Math.abs(shown) < 1e-3 || Math.abs(shown) >= 1e6);
        text = tiny ? shown.toExponential(f.precision - 1) : shown.toPrecision(f.precision);
      }
      else { attributes["data-digits"] = f.digits; text = shown.toFixed(f.digits); }
    } else {
      attributes["data-digits"] = f.digits;
    }
    attributes.text = text;
    return node("span", Object.assign({ class: "metric" }, attributes));
  }

  function meanStd(pointer, format) {
    const parts = [metricSpan(`${pointer}/mean`, format)];
    if (typeof lookup(metrics, `${pointer}/std`) === "number") parts.push(" \u00b1 ", metricSpan(`${pointer}/std`, format));
    return parts;
  }

  const colormaps = {};
  for (const [name, hex] of Object.entries(data.colormaps || {})) {
    const lut = new Uint8Array(hex.length / 2);
    for (let i = 0; i < lut.length; ++i) lut[i] = parseInt(hex.substr(2 * i, 2), 16);
    colormaps[name] = lut;
  }

  // A colour bar for `scale` ({colormap, range, unit, pointers?, factor?}): ends labelled with the
  // range, times `factor` where one is given (the uncertainty score, shown divided by lambda).
  function scaleBar(scale) {
    const canvas = node("canvas", { width: 256, height: 1 });
    const context = canvas.getContext("2d");
    const image = context.createImageData(256, 1);
    const lut = colormaps[scale.colormap];
    for (let i = 0; i < 256; ++i) {
      image.data.set([lut[3 * i], lut[3 * i + 1], lut[3 * i + 2], 255], 4 * i);
    }
    context.putImageData(image, 0, 0);
    const factor = scale.factor || 1;
    const end = (k) =>
        (scale.pointers ? metricSpan(scale.pointers[k], {precision: 3, factor}, scale.source) :
                          node('span', {text: (factor * Number(scale.range[k])).toPrecision(4)}));
    return node("div", { class: "scale" }, [
      canvas, node("div", { class: "ticks" }, [end(0), node("span", { text: scale.unit }), end(1)])]);
  }

  // ---- header ----
  const frames = data.frames;
  const subtitle = [];
  if (frames) {
    const noun = (data.kind === 'render' ? 'view' : 'frame') + (frames.count === 1 ? '' : 's');
    subtitle.push(
        frames.sizes_vary ?
            `${frames.count} ${noun} of several sizes` :
            `${frames.count} ${noun}, ${frames.source_width}\u00d7${frames.source_height} pixels`);
  }
  subtitle.push(`written ${data.run.written}`, `endorecon ${data.run.version}`);
  if (metrics.cancelled) subtitle.push("CANCELLED before the end: no frames were evaluated");
  $("subtitle").textContent = subtitle.join(" \u00b7 ");

  // What a reader must know before trusting the numbers, above them.
  const warn = (children) => $('warnings').appendChild(node('p', {class: 'warning'}, children));
  // The run's own (metrics.json "warnings": a run that learnt nothing, a mesh with no triangle).
  for (const text of metrics.warnings || []) warn([text.charAt(0).toUpperCase() + text.slice(1) + '.']);
  if (metrics.time && metrics.time.budget_advised_s) {
    warn([
      'The time budget was too small for this clip: training had ',
      metricSpan('/time/training_s', {digits: 1}), ' s of the run\'s ',
      metricSpan('/time/total_s', {digits: 1}), ' s (', metricSpan('/iterations', {digits: 0}),
      ' iterations) because rendering the results needed the rest, so the model is likely underfitted. ',
      'A budget of ', metricSpan('/time/budget_advised_s', {digits: 0}),
      ' s or more leaves training three quarters of the run.'
    ]);
  }
  const evaluation = metrics.evaluation || {};
  const reducedFrames = new Set(evaluation.reduced_frames || []);
  if (reducedFrames.size > 0) {
    warn([
      `${reducedFrames.size} of the ${
          (evaluation.full_frames || []).length + reducedFrames.size} evaluated frames ` +
          'were rendered reduced, to keep evaluation to its share of the run: their colour and depth come from one pass ' +
          'without dropout, their uncertainty maps from a coarser grid, upsampled. Their scores are a little worse than ' +
          'a full render\'s; compare full frames with full frames (the per-frame table\'s render column, hollow markers ' +
          'in its plots). ',
      node('code', {text: 'reconstruct --full-eval'}), ' renders every frame full.'
    ]);
  }
  if (data.kind === 'reconstruction' && data.depth_measured === false) {
    warn([
      'The clip has no depth images and no second eye, so the depth has no absolute scale: it is in clip units ',
      'set by the clip\'s near and far bounds, and the 3D surface shows shape only.'
    ]);
  }

  // The clip's near-far range the relative depth errors divide by, as " (40.0-130.0 clip units)".
  function depthRangeText() {
    const bounds = data.depth_bounds;
    if (!bounds) return '';
    return ` (${bounds[0].toFixed(1)}\u2013${bounds[1].toFixed(1)} clip units)`;
  }

  function card(label, value, extra) {
    return node("div", { class: "card" }, [node("div", { class: "label", text: label }),
                                           node("div", { class: "value" }, value),
                                           node("div", { class: "extra" }, extra || [])]);
  }
  const reported = metrics.heldout ? "heldout" : "train";
  const splitName = reported === "heldout" ? "held-out" : "training";
  const summary = $("summary");
  if (data.kind === "reconstruction") {
    if (lookup(metrics, `/${reported}/image`)) {
      summary.append(card(`${splitName} PSNR, tissue (dB)`, meanStd(`/${reported}/image/psnr_tissue`),
                          [metricSpan(`/${reported}/image/psnr_tissue/count`, { digits: 0 }), " frames"]));
      summary.append(card(`${splitName} SSIM, tissue`, meanStd(`/${reported}/image/ssim_tissue`, { digits: 4 })));
    }
    if (lookup(metrics, `/${reported}/depth`)) {
      summary.append(
          card(`${splitName} depth RMSE (clip units)`, meanStd(`/${reported}/depth/rmse`, {digits: 3}), [
            metricSpan(`/${reported}/depth/rmse_relative/mean`, {digits: 2, factor: 100}),
            ` % of the near\u2013far range${depthRangeText()}`
          ]));
    }
    if (lookup(metrics, `/${reported}/calibration`)) {
      summary.append(card(`${splitName} Spearman (uncertainty, error)`, meanStd(`/${reported}/calibration/spearman`, { digits: 3 })));
      summary.append(card(`${splitName} AUSE`, meanStd(`/${reported}/calibration/ause`, { digits: 3 })));
    }
    // Where the clip has its noise-free truth: how well the model map finds where the model is wrong.
    if (lookup(metrics, `/${reported}/calibration_model_map_noise_free`)) {
      summary.append(card(`${splitName} Spearman (model map, noise-free error)`,
                          meanStd(`/${reported}/calibration_model_map_noise_free/spearman`, { digits: 3 })));
    }
    summary.append(card(
        'training',
        [metricSpan('/iterations', {digits: 0}), metrics.iterations === 1 ? ' iteration' : ' iterations'], [
          metricSpan('/train_seconds', {digits: 1}), ' s of steps, ',
          metricSpan('/samples_per_second', {digits: 2, factor: 1e-6}), ' M samples/s'
        ]));
  } else {
    summary.append(card("views", [node("span", { text: String(frames ? frames.count : 0) })]));
    summary.append(card("dropout passes (uncertainty)", [node("span", { text: String(data.render.mc_passes) })]));
  }

  // ---- frames ----
  const splitOf = new Map();
  for (const split of ["train", "heldout"]) {
    (lookup(metrics, `/${split}/frames`) || []).forEach((frame, position) => splitOf.set(frame, { split, position }));
  }
  const panelDefs = [
    { key: "input", label: "input (the clip)" },
    { key: "rendered", label: "rendered" },
    { key: "depth", label: "rendered depth", scale: "depth" },
    { key: "uncertainty", label: "total uncertainty", scale: "uncertainty" },
    { key: "model", label: "model map: where the model is likely wrong", scale: "model" },
    { key: "error", label: "error against the input (RMSE over RGB)", scale: "error" },
  ];
  const panels = [];
  let current = 0;
  if (frames && frames.count > 0) {
    const slider = $("frame-slider");
    slider.max = String(frames.count - 1);
    for (const def of panelDefs) {
      if (!frames[def.key]) continue;
      const image = node("img", { alt: def.label, "data-layer": def.key });
      const overlay = frames.tool ? node("img", { class: "overlay", alt: "", "data-layer": "tool" }) : null;
      const figure = node("figure", { class: "panel", style: `max-width:${Math.max(240, 2 * frames.width)}px` }, [
        node("div", { class: "stack" }, overlay ? [image, overlay] : [image]),
        node("figcaption", { text: def.label })]);
      if (def.scale && data.scales[def.scale]) figure.appendChild(scaleBar(data.scales[def.scale]));
      $("panels").appendChild(figure);
      panels.push({ key: def.key, image, overlay });
    }
    // The heat maps' scales are this run's own (docs/formats.md, heatmap_scale): say so once.
    if (data.scales.uncertainty || data.scales.model || data.scales.error) {
      $('frames-section').appendChild(node('p', {
        class: 'note',
        text:
            'Each heat map\'s colours run from 0 to the 99th percentile of this run\'s values on tissue, the same ' +
            'for every frame of the run: compare colours within a run, not between runs.' +
            (data.scales.uncertainty && data.scales.uncertainty.factor ?
                 ' The total uncertainty\'s bar is its score divided by lambda (uncertainty_lambda): the ' +
                     'colour\'s variance, RGB in [0, 1], squared.' :
                 '')
      }));
    }
    $("tool-shading").addEventListener("change", () => showFrame(current));
    if (!frames.tool) $("tool-shading").parentElement.style.display = "none";
    // The mask covers tools and, on a real scope, the dark corners outside its view: both are left out.
    if (data.recording)
      $('tool-shading').nextSibling.textContent = ' shade masked pixels (tools, outside the view)';
    slider.addEventListener("input", () => showFrame(Number(slider.value)));
    let timer = null;
    $("play").addEventListener("click", () => {
      if (timer) {
        clearInterval(timer);
        timer = null;
        $("play").textContent = "\u25b6 play";
        $('play').setAttribute('aria-label', 'play');
      } else {
        timer = setInterval(() => showFrame((current + 1) % frames.count), 125);
        $("play").textContent = "\u275a\u275a pause";
        $('play').setAttribute('aria-label', 'pause');
      }
    });
  } else {
    $("frames-section").appendChild(node("p", { class: "missing", text: "No frames were rendered." }));
    $("frame-slider").disabled = true;
    $("play").disabled = true;
  }

  function frameMetricsLine(frame) {
    const where = splitOf.get(frame);
    if (!where) return [];
    const base = `/${where.split}`;
    const at = (group, key) => `${base}/${group}/per_frame/${where.position}/${key}`;
    const parts = ["PSNR ", metricSpan(at("image", "psnr")), " dB (tissue ", metricSpan(at("image", "psnr_tissue")),
                   ") \u00b7 SSIM ", metricSpan(at("image", "ssim"), { digits: 4 }), " (tissue ",
                   metricSpan(at("image", "ssim_tissue"), { digits: 4 }), ")"];
    if (lookup(metrics, `${base}/depth`)) parts.push(" \u00b7 depth RMSE ", metricSpan(at("depth", "rmse"), { digits: 3 }));
    if (lookup(metrics, `${base}/calibration`)) {
      parts.push(" \u00b7 Spearman ", metricSpan(at("calibration", "spearman"), { digits: 3 }),
                 " \u00b7 AUSE ", metricSpan(at("calibration", "ause"), { digits: 3 }));
    }
    if (reducedFrames.has(frame)) parts.push(' \u00b7 reduced render');
    return parts;
  }

  let viewer = null;
  function showFrame(frame) {
    current = frame;
    $("frame-slider").value = String(frame);
    for (const panel of panels) {
      panel.image.src = frames[panel.key][frame];
      if (panel.overlay) {
        panel.overlay.src = frames.tool[frame];
        panel.overlay.style.display = $("tool-shading").checked ? "" : "none";
      }
    }
    const where = splitOf.get(frame);
    const label = $("frame-label");
    // A recording's frames also by their time in it (t is the clip's, 0 to 1).
    const seconds = data.recording && data.recording.times_s ? data.recording.times_s[frame] : undefined;
    label.replaceChildren(
        `${data.kind === 'render' ? 'view' : 'frame'} ${frame} / ${frames.count - 1} \u00b7 t = ` +
        `${frames.times[frame].toFixed(3)}` +
        (typeof seconds === 'number' ? ` (${seconds.toFixed(2)} s into the recording) ` : ' '));
    label.dataset.frame = String(frame);
    if (where) label.appendChild(node("span", { class: `badge ${where.split}`, text: where.split === "heldout" ? "held out" : "trained on" }));
    $("frame-metrics").replaceChildren(...frameMetricsLine(frame));
    for (const row of document.querySelectorAll("#per-frame-table tr.current")) row.classList.remove("current");
    const row = document.querySelector(`#per-frame-table tr[data-frame="${frame}"]`);
    if (row) row.classList.add("current");
    if (viewer) viewer.showFrame(frame);
  }

  // ---- 3D surface ----
  // Started after the first paint: a browser's first WebGL context can take a second (starting its GPU
  // process, or a software renderer without a GPU), and the rest of the page need not wait for it.
  function startSurface() {
    try {
      viewer = new SurfaceViewer($("surface"), data.surface, colormaps.inferno);
      viewer.showFrame(current);
      const select = $("surface-colour");
      // A heat-map colouring shows its scale bar; one the results have no scale (or grid) for is disabled.
      const heats = { uncertainty: "uncertainty colouring", model: "model map colouring" };
      const surfaceScale = () => {
        // Only a colouring with a scale shows one (a script may pick a disabled option).
        const heat = data.scales[select.value] ? heats[select.value] : undefined;
        $("surface-scale").replaceChildren(...(heat ? [node("div", { class: "hint", text: heat }),
                                                       scaleBar(data.scales[select.value])] : []));
        $("surface-scale").style.visibility = heat ? "visible" : "hidden";
      };
      for (const key of Object.keys(heats)) {
        const present = data.scales[key] && (key !== "model" || data.surface.frames.every((f) => f.model));
        if (!present) select.querySelector(`option[value="${key}"]`).disabled = true;
      }
      select.addEventListener("change", () => {
        viewer.setColouring(select.value);
        surfaceScale();
      });
      surfaceScale();
      $('surface-note').textContent =
          `The frame's rendered depth back-projected through its camera, one point per ` +
          `${data.surface.stride} \u00d7 ${data.surface.stride} pixels (clip units); masked pixels (tools, ` +
          `outside the view) are left out.`;
    } catch (error) {
      viewer = null;
      $("surface-note").textContent = `The 3D view needs WebGL, which this browser did not provide (${error.message}).`;
    }
  }
  const hasSurface = data.surface && data.surface.frames.length > 0;
  if (!hasSurface) {
    $("surface-section").appendChild(node("p", { class: "missing", text: "No surface: no frames were rendered." }));
  }

  // ---- error against run time ----
  const curve = metrics.curve || [];
  if (curve.length > 0) {
    const seconds = curve.map((p) => p.seconds);
    const field = (key, factor) => curve.map((p) => (typeof p[key] === "number" ? p[key] * (factor || 1) : NaN));
    const last = curve.length - 1;
    const psnrPlot = EndoPlots.linePlot({
      title: 'PSNR against training time',
      xLog: true,
      xLabel: 'training time (s, log scale)',
      yLabel: 'PSNR (dB)',
      xName: 's',
      series: [
        {label: 'held-out (tissue)', x: seconds, y: field('heldout_psnr')},
        {label: 'training batch', x: seconds, y: field('train_psnr'), dashed: true}
      ],
    });
    const psnrLast = ["last point, ", metricSpan(`/curve/${last}/seconds`, { digits: 1 }), " s: "];
    if (typeof curve[last].heldout_psnr === "number") psnrLast.push("held-out ", metricSpan(`/curve/${last}/heldout_psnr`), " dB, ");
    psnrLast.push("training batch ", metricSpan(`/curve/${last}/train_psnr`), " dB");
    psnrPlot.appendChild(node("figcaption", { class: "numbers" }, psnrLast));
    $("curve-plots").appendChild(psnrPlot);
    if (curve.some((p) => typeof p.heldout_depth_rmse_relative === "number")) {
      const depthPlot = EndoPlots.linePlot({
        title: 'Depth error against training time',
        xLog: true,
        xLabel: 'training time (s, log scale)',
        yLabel: 'depth RMSE, % of near\u2013far (log)',
        yLog: true,
        xName: 's',
        series: [
          {label: 'held-out', x: seconds, y: field('heldout_depth_rmse_relative', 100), colour: '#c2410c'}
        ],
      });
      depthPlot.appendChild(node('figcaption', {class: 'numbers'}, [
        'last point: ', metricSpan(`/curve/${last}/heldout_depth_rmse_relative`, {digits: 2, factor: 100}),
        ` % of the near\u2013far range${depthRangeText()}`
      ]));
      $("curve-plots").appendChild(depthPlot);
    }
    $("curve-plots").appendChild(node("p", { class: "note", text:
      "Measured during training on a fixed subset of held-out pixels; the seconds are training time only." }));
  } else {
    $("curve-section").appendChild(node("p", { class: "missing", text: "No curve was recorded." }));
  }

  // ---- per-frame metrics ----
  const columns = [
    {group: 'image', key: 'psnr', label: 'PSNR (dB)'},
    {group: 'image', key: 'psnr_tissue', label: 'PSNR tissue (dB)'},
    {group: 'image', key: 'ssim', label: 'SSIM', digits: 4},
    {group: 'image', key: 'ssim_tissue', label: 'SSIM tissue', digits: 4},
    {group: 'depth', key: 'rmse', label: 'depth RMSE (clip units)', digits: 3},
    {group: 'depth', key: 'mae', label: 'depth MAE (clip units)', digits: 3},
    {group: 'calibration', key: 'pearson', label: 'Pearson', digits: 3},
    {group: 'calibration', key: 'spearman', label: 'Spearman', digits: 3},
    {group: 'calibration', key: 'ause', label: 'AUSE', digits: 3},
  ].filter((c) => lookup(metrics, `/train/${c.group}`) || lookup(metrics, `/heldout/${c.group}`));
  const evaluated = [...splitOf.keys()].sort((a, b) => a - b);
  if (evaluated.length > 0) {
    const table = $("per-frame-table");
    const mixed = reducedFrames.size > 0;
    table.appendChild(node('tr', {}, [
      node('th', {text: 'frame'}), node('th', {text: 't (0\u20131)'}),
      node('th', {class: 'text', text: 'split'}),
      ...(mixed ? [node('th', {class: 'text', text: 'render'})] : []),
      ...columns.map((c) => node('th', {text: c.label}))
    ]));
    for (const frame of evaluated) {
      const where = splitOf.get(frame);
      const cells = columns.map((c) => node("td", {}, [metricSpan(`/${where.split}/${c.group}/per_frame/${where.position}/${c.key}`,
                                                                   { digits: c.digits || 2 })]));
      const row = node('tr', {class: where.split, 'data-frame': frame}, [
        node('td', {text: String(frame)}), node('td', {text: frames ? frames.times[frame].toFixed(3) : ''}),
        node('td', {class: 'text', text: where.split === 'heldout' ? 'held out' : 'trained on'}),
        ...(mixed ? [node('td', {class: 'text', text: reducedFrames.has(frame) ? 'reduced' : 'full'})] : []),
        ...cells
      ]);
      if (frames && frames.count > 0) {
        // Shown by a click, or from the keyboard: Tab to the row, Enter or Space.
        row.tabIndex = 0;
        row.setAttribute('aria-label', `show frame ${frame}`);
        row.addEventListener('click', () => showFrame(frame));
        row.addEventListener('keydown', (event) => {
          if (event.key !== 'Enter' && event.key !== ' ') return;
          event.preventDefault();
          showFrame(frame);
        });
      }
      table.appendChild(row);
    }
    const perFrame = (split, group, key) => {
      const list = lookup(metrics, `/${split}/frames`) || [];
      return { x: list, y: list.map((_, i) => { const v = lookup(metrics, `/${split}/${group}/per_frame/${i}/${key}`); return typeof v === "number" ? v : NaN; }) };
    };
    // Reduced renders hollow, apart from the full ones (their scores are a little worse).
    const series = (group, key) => {
      const out = [];
      for (const s of ['train', 'heldout'].filter((split) => metrics[split])) {
        const all = perFrame(s, group, key);
        for (const reduced of [false, true]) {
          const keep = all.x.map((frame) => reducedFrames.has(frame) === reduced);
          if (!keep.some(Boolean)) continue;
          const name = s === 'heldout' ? 'held out' : 'trained on';
          out.push({
            label: mixed ? `${name}, ${reduced ? 'reduced' : 'full'}` : name,
            markersOnly: true,
            hollow: reduced,
            colour: s === 'heldout' ? '#c2410c' : '#1f6feb',
            x: all.x.filter((_, i) => keep[i]),
            y: all.y.filter((_, i) => keep[i])
          });
        }
      }
      return out;
    };
    $('per-frame-plot').appendChild(EndoPlots.linePlot({
      title: 'PSNR per frame (tissue)',
      xLabel: 'frame',
      xName: 'frame',
      yLabel: 'PSNR (dB)',
      series: series('image', 'psnr_tissue')
    }));
    if (columns.some((c) => c.group === "depth")) {
      $('per-frame-plot').appendChild(EndoPlots.linePlot({
        title: 'Depth RMSE per frame',
        xLabel: 'frame',
        xName: 'frame',
        yLabel: 'RMSE (clip units)',
        series: series('depth', 'rmse')
      }));
    }
  } else {
    $("per-frame-section").appendChild(node("p", { class: "missing", text: "No frame was evaluated." }));
  }

  // ---- calibration ----
  const calibrated = ["heldout", "train"].filter((s) => lookup(metrics, `/${s}/calibration/curves`));
  for (const split of calibrated) {
    const curves = lookup(metrics, `/${split}/calibration/curves`);
    const name = split === "heldout" ? "held-out" : "training";
    const plot = EndoPlots.linePlot({
      title: `Sparsification, ${name} frames`, xLabel: "fraction of pixels removed", yLabel: "mean error / mean error at 0",
      series: [{ label: "by uncertainty", x: curves.fractions, y: curves.by_uncertainty },
               { label: "oracle (by error)", x: curves.fractions, y: curves.oracle, dashed: true }],
    });
    const base = `/${split}/calibration`;
    plot.appendChild(node("figcaption", { class: "numbers" }, [
      "Spearman ", ...meanStd(`${base}/spearman`, { digits: 3 }), " \u00b7 Pearson ", ...meanStd(`${base}/pearson`, { digits: 3 }),
      " \u00b7 AUSE ", ...meanStd(`${base}/ause`, { digits: 3 })]));
    plot.appendChild(node("figcaption", { text:
      "Pixels removed in order of uncertainty against in order of their true error; AUSE is the area between." }));
    $("calibration").appendChild(plot);
  }
  // Where the clip has its noise-free truth: how well each map finds where the model itself is wrong.
  for (const split of calibrated) {
    const model = lookup(metrics, `/${split}/calibration_model_map_noise_free/curves`);
    const paper = lookup(metrics, `/${split}/calibration_noise_free/curves`);
    if (!model || !paper) continue;
    const name = split === "heldout" ? "held-out" : "training";
    const plot = EndoPlots.linePlot({
      title: `Sparsification of the noise-free error, ${name} frames`, xLabel: "fraction of pixels removed",
      yLabel: "mean error / mean error at 0",
      series: [{ label: "model map", x: model.fractions, y: model.by_uncertainty, colour: "#7c3aed" },
               { label: "uncertainty", x: paper.fractions, y: paper.by_uncertainty, colour: "#1f6feb" },
               { label: "oracle", x: model.fractions, y: model.oracle, dashed: true, colour: "#c2410c" }],
    });
    const base = `/${split}/calibration_model_map_noise_free`;
    plot.appendChild(node("figcaption", { class: "numbers" }, [
      "model map: Spearman ", ...meanStd(`${base}/spearman`, { digits: 3 }),
      " \u00b7 AUSE ", ...meanStd(`${base}/ause`, { digits: 3 })]));
    plot.appendChild(node("figcaption", { text:
      "Against the clip's noise-free truth: where the reconstruction is wrong, apart from the camera's noise." }));
    $("calibration").appendChild(plot);
  }
  if (calibrated.length === 0) {
    $("calibration-section").appendChild(node("p", { class: "missing", text: "No uncertainty calibration was measured." }));
  }

  // ---- what was left out (and what a measurement kept), the run ----
  const leftOut = metrics.left_out || [];
  const kept = metrics.kept || [];
  const reasons = (heading, items) => {
    if (items.length === 0) return;
    $('left-out').appendChild(node('tr', {}, [
      node('th', {class: 'text', text: heading}), node('th', {class: 'text', text: 'why'})
    ]));
    for (const item of items)
      $('left-out').appendChild(node('tr', {}, [
        node('td', {text: item.what}), node('td', {text: item.why})
      ]));
  };
  reasons('left out', leftOut);
  reasons('kept, as measured', kept);
  if (leftOut.length === 0) {
    $('left-out-section').appendChild(node('p', {
      class: 'missing',
      text: data.kind === 'render' ? 'See the reconstruction\'s own report.' :
                                     'Nothing left out: the clip needed every part.'
    }));
  }
  const runRows = [];
  const run = data.run;
  runRows.push(["machine", `${run.machine.hostname}: ${run.machine.cpu}, ${run.machine.logical_cores} logical cores, ` +
                           `${run.machine.memory_gib.toFixed(1)} GiB memory, ${run.machine.os}`]);
  runRows.push(["device", run.device], ["written", run.written], ["version", `endorecon ${run.version}`]);
  if (data.clip) runRows.push([data.kind === 'render' ? 'rendered from' : 'clip', data.clip]);
  const recording = data.recording;
  if (recording) {
    const parts = [recording.source || 'a recording'];
    const window = recording.frames;
    if (window && typeof window.start === 'number') {
      parts.push(`frames ${window.start}:${window.end}:${window.step} of its ${recording.recording_frames}`);
    }
    if (recording.fps > 0) parts.push(`at most ${recording.fps} frames a second`);
    if (recording.size && recording.recorded_size) {
      parts.push(
          `${recording.size[0]}\u00d7${recording.size[1]} pixels from ${recording.recorded_size[0]}\u00d7` +
          `${recording.recorded_size[1]}`);
    }
    if (recording.stereo) parts.push(recording.stereo === 'mono' ? 'mono' : `stereo (${recording.stereo})`);
    if (recording.endoscope) parts.push(`endoscope ${recording.endoscope}`);
    runRows.push(['recording', parts.join('; ')]);
  }
  if (metrics.time) {
    // Where the run's time went, against its budget; and, when the clip's results cost more than
    // evaluation's quarter of it, the budget that would have left training its three quarters.
    const seconds = (key) => metricSpan(`/time/${key}`, { digits: 1 });
    const time = [seconds("total_s"), " s"];
    if (metrics.time.budget_s > 0) time.push(" of a ", seconds("budget_s"), " s budget");
    time.push(
        ': training ', seconds('training_s'), ' s (', metricSpan('/train_seconds', {digits: 1}),
        ' s of it steps, the rest periodic work), evaluation ', seconds('evaluation_s'), ' s, writing ',
        seconds('writing_s'), ' s');
    if (metrics.time.budget_advised_s) {
      time.push(
          '; rendering the results was priced, before it ran, at about ',
          metricSpan('/evaluation/seconds/render_least', {digits: 0}), ' s at the least (it took ',
          metricSpan('/evaluation/seconds/render', {digits: 1}), ' s), so training gave way: a budget of ',
          metricSpan('/time/budget_advised_s', {digits: 0}),
          ' s or more leaves it three quarters of the run');
    }
    runRows.push(["time", time]);
  }
  if (metrics.field) runRows.push(["field", [node("span", { class: "lines", text: metrics.field })]]);
  if (evaluation.full) {
    const how = [`full (${(evaluation.full_frames || []).length} frames): ${evaluation.full}`];
    if (reducedFrames.size > 0) how.push(`reduced (${reducedFrames.size} frames): ${evaluation.reduced}`);
    runRows.push(['evaluation', [node('span', {class: 'lines', text: how.join('\n')})]]);
  }
  if (metrics.evaluation_mask) runRows.push(["evaluation mask", metrics.evaluation_mask]);
  if (metrics.video) {
    runRows.push(["video", [`${metrics.video.path} (${metrics.video.codec}, `, metricSpan("/video/frames", { digits: 0 }), " frames)"]]);
  }
  // The uncertainty estimator's settings: metrics.json's for a reconstruction, render.json's for views.
  const settings = metrics.uncertainty_maps || data.render;
  if (settings && settings.mc_passes !== undefined) {
    const number = (key, format) =>
        (data.metrics ? metricSpan(`/uncertainty_maps/${key}`, format) :
                        metricSpan(`/${key}`, format, 'render'));
    runRows.push(["uncertainty", [`${settings.score}; `, number("mc_passes", { digits: 0 }), " dropout passes, lambda ",
                                  number("lambda", { precision: 3 }), ", variance floor ",
                                  number("variance_eps", { precision: 3 })]]);
  }
  for (const [key, value] of runRows) {
    $("run").appendChild(node("tr", {}, [node("th", { text: key }), node("td", {}, Array.isArray(value) ? value : [String(value)])]));
  }

  // The configuration as pointer -> value rows (config.json, or render.json for a render's views).
  const flat = [];
  const walk = (value, pointer) => {
    if (value && typeof value === "object" && !Array.isArray(value)) {
      for (const [key, child] of Object.entries(value)) walk(child, `${pointer}/${key}`);
    } else {
      flat.push([pointer, value]);
    }
  };
  walk(data.config || data.render || {}, "");
  for (const [pointer, value] of flat) {
    const cell = typeof value === "number" && data.config
      ? node("td", {}, [node("span", { "data-config": pointer, text: String(value) })])
      : node("td", { text: JSON.stringify(value) });
    $("config").appendChild(node("tr", {}, [node("th", { text: pointer.slice(1) }), cell]));
  }

  // A printed page shows the configuration too.
  window.addEventListener('beforeprint', () => {
    for (const d of document.querySelectorAll('details')) d.open = true;
  });

  if (frames && frames.count > 0) showFrame(0);
  // When the page was built, in ms since navigation (bench/report_page_bench reads them): shownMs for
  // everything but the 3D view, readyMs for all; "ready" marks the end.
  const done = () => {
    document.body.dataset.readyMs = performance.now().toFixed(0);
    document.body.dataset.ready = "true";
  };
  document.body.dataset.shownMs = performance.now().toFixed(0);
  if (hasSurface) {
    requestAnimationFrame(() => setTimeout(() => {
      startSurface();
      done();
    }, 0));
  } else {
    done();
  }
})();
