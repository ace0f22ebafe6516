// Draws every chart of the JSON in #plot-data into its <div id=...> (uPlot, one per
// panel); a panel's bands (the speed plot's slowdowns) are shaded and labelled, and
// its ybands (the process quality's band) shaded across the plot.
(() => {
  const D = JSON.parse(document.getElementById("plot-data").textContent);
  const sync = uPlot.sync("t");
  // Shaded time bands (the speed plot's slowdowns), each labelled at its top.
  const drawBands = (u, bands) => {
    const ctx = u.ctx, top = u.bbox.top, height = u.bbox.height;
    ctx.save();
    ctx.font = `${Math.round(10 * devicePixelRatio)}px sans-serif`;
    for (const b of bands) {
      const x0 = u.valToPos(b.t0, "x", true), x1 = u.valToPos(b.t1, "x", true);
      ctx.fillStyle = "rgba(255, 160, 0, 0.15)";
      ctx.fillRect(x0, top, Math.max(x1 - x0, 1), height);
      ctx.fillStyle = "#b36b00";
      ctx.fillText(b.label, x0 + 2, top + 12 * devicePixelRatio);
    }
    ctx.restore();
  };
  // Shaded value bands (the process quality's band), each labelled at its left.
  const drawYBands = (u, ybands) => {
    const ctx = u.ctx, left = u.bbox.left, width = u.bbox.width;
    ctx.save();
    ctx.font = `${Math.round(10 * devicePixelRatio)}px sans-serif`;
    for (const b of ybands) {
      const y0 = u.valToPos(b.y0, "y", true), y1 = u.valToPos(b.y1, "y", true);
      ctx.fillStyle = "rgba(46, 125, 50, 0.15)";
      ctx.fillRect(left, Math.min(y0, y1), width, Math.max(Math.abs(y1 - y0), 1));
      ctx.fillStyle = "#2e7d32";
      ctx.fillText(b.label, left + 4, Math.min(y0, y1) + 12 * devicePixelRatio);
    }
    ctx.restore();
  };
  for (const plot of D.plots) {
    const box = document.getElementById(plot.id);
    const width = Math.floor((box.clientWidth || 1100) / plot.columns) - 8;
    for (const panel of plot.panels) {
      const x = D.columns[panel.x || "t"];
      const ys = panel.series.map(s => s.col ? D.columns[s.col] : x.map(() => s.const));
      const cell = document.createElement("div");
      cell.className = "panel";
      box.appendChild(cell);
      new uPlot({
        title: panel.title || "", width: width, height: plot.columns > 1 ? 220 : 300,
        cursor: {sync: {key: sync.key}},
        scales: panel.yrange ? {x: {time: false}, y: {range: panel.yrange}} : {x: {time: false}},
        axes: [{label: panel.x ? "time t [s]" : "time t [s]"}, {label: panel.ylabel}],
        series: [{label: "t [s]"}].concat(panel.series.map(s => ({
          label: s.label, stroke: s.color, width: 1.3, dash: s.dash ? [6, 4] : undefined,
        }))),
        hooks: {drawClear: [
          u => drawBands(u, panel.bands || []), u => drawYBands(u, panel.ybands || []),
        ]},
      }, [x].concat(ys), cell);
    }
  }
  document.body.dataset.plotsDrawn = String(document.querySelectorAll(".uplot").length);
})();
