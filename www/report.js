// The run report as cards: one per stage (label, "reused" badge when its output came from the
// previous run), its metrics, plots (plot.js) and tables. Stages, metrics, plots and tables
// all come from the report: nothing here knows a job kind.

import { renderPlot, plotGroups, formatNumber, axisTitle } from "./plot.js";

/**
 * Group indices a stage report uses (plots, tables, metrics with a group), sorted, and the
 * group's name ("Layer").
 */
export function stageGroups(stage) {
  const set = new Set();
  let name = null;
  for (const p of stage.plots ?? []) {
    for (const g of plotGroups(p)) set.add(g);
    if (p.group) name ??= p.group;
  }
  for (const t of stage.tables ?? []) {
    if (!t.group) continue;
    name ??= t.group;
    for (const r of t.rows ?? []) if (Number.isInteger(r.group_index)) set.add(r.group_index);
  }
  for (const m of stage.metrics ?? []) if (Number.isInteger(m.group_index)) set.add(m.group_index);
  return { indices: [...set].sort((a, b) => a - b), name: name ?? "Group" };
}

/**
 * Renders every stage report into `host` (replacing its cards).
 * @param {HTMLElement} host
 * @param {Object|null} report  the RunReport
 * @param {{groups: Map<string, number>}} state  chosen group per stage name (kept across runs)
 */
export function renderReport(host, report, state) {
  const stages = report?.stages ?? [];
  const cards = stages.filter(hasContent).map((stage) => {
    const card = document.createElement("section");
    card.className = "card stage-card";
    card.dataset.stage = stage.stage;
    card.setAttribute("aria-label", stage.label ?? stage.stage);
    fillCard(card, stage, state);
    return card;
  });
  host.replaceChildren(...cards);
  host.hidden = cards.length === 0;
  return cards.length;
}

function hasContent(stage) {
  return (stage.metrics?.length ?? 0) + (stage.plots?.length ?? 0) + (stage.tables?.length ?? 0) + (stage.notes?.length ?? 0) > 0;
}

function fillCard(card, stage, state) {
  card.replaceChildren();
  const wide = (stage.plots?.length ?? 0) > 0 || (stage.tables?.length ?? 0) > 0;
  card.classList.toggle("wide", wide);
  card.dataset.cached = String(Boolean(stage.cached));
  const head = document.createElement("div");
  head.className = "card-head";
  const h2 = document.createElement("h2");
  h2.textContent = stage.label ?? stage.stage;
  head.append(h2);
  if (stage.cached) {
    const badge = document.createElement("span");
    badge.className = "badge reused";
    badge.textContent = "reused";
    badge.title = "This stage's output was reused from the previous run: nothing it depends on changed.";
    head.append(badge);
  }
  const { indices, name } = stageGroups(stage);
  let group = null;
  if (indices.length) {
    const chosen = state.groups.get(stage.stage);
    group = indices.includes(chosen) ? chosen : indices[0];
    const id = `group-${stage.stage}`;
    const label = document.createElement("label");
    label.className = "inline";
    label.htmlFor = id;
    label.textContent = name.toLowerCase();
    const select = document.createElement("select");
    select.id = id;
    select.className = "group-select";
    for (const i of indices) select.append(new Option(`${i + 1} of ${indices.length}`, String(i)));
    select.value = String(group);
    select.addEventListener("change", () => {
      state.groups.set(stage.stage, Number(select.value));
      fillCard(card, stage, state);
      card.querySelector(".group-select")?.focus();
    });
    const hidden = indices.length < 2;
    label.hidden = hidden;
    select.hidden = hidden;
    head.append(label, select);
  }
  card.dataset.group = group === null ? "" : String(group);
  card.append(head);
  // What the stage repaired or assumed (a capped hole, the grounded joints): said first.
  if (stage.notes?.length) {
    const notes = document.createElement("ul");
    notes.className = "stage-notes";
    notes.setAttribute("role", "note");
    for (const text of stage.notes) {
      const li = document.createElement("li");
      li.textContent = text;
      notes.append(li);
    }
    card.append(notes);
  }

  const metrics = (stage.metrics ?? []).filter((m) => !Number.isInteger(m.group_index) || m.group_index === group);
  if (metrics.length) card.append(metricList(metrics));
  for (const plot of stage.plots ?? []) {
    const fig = document.createElement("figure");
    fig.className = `plot-figure plot-${plot.kind}`;
    if (plot.title) {
      const cap = document.createElement("figcaption");
      cap.textContent = plot.group && group !== null && indices.length > 1 ? `${plot.title} · ${plot.group.toLowerCase()} ${group + 1}` : plot.title;
      fig.append(cap);
    }
    const svg = document.createElementNS("http://www.w3.org/2000/svg", "svg");
    renderPlot(svg, plot, { group });
    fig.append(svg);
    card.append(fig);
  }
  for (const table of stage.tables ?? []) card.append(tableOf(table, group));
}

/**
 * A <dl> of label / value (unit) pairs; numbers are formatted, text is shown as it is.
 * @param {Array<{key?: string, label?: string, value: number|string, unit?: string, hint?: string}>} metrics
 */
export function metricList(metrics, className = "metrics") {
  const dl = document.createElement("dl");
  if (className) dl.className = className;
  for (const m of metrics) {
    const div = document.createElement("div");
    if (m.key) div.dataset.key = m.key;
    if (m.hint) div.title = m.hint;
    const dt = document.createElement("dt");
    dt.textContent = m.label ?? m.key;
    const dd = document.createElement("dd");
    dd.textContent = formatNumber(m.value, 3);
    if (m.unit) {
      const u = document.createElement("span");
      u.className = "unit";
      u.textContent = ` ${m.unit}`;
      dd.append(u);
    }
    div.append(dt, dd);
    // What the number means, in one line where it is shown (a tooltip is not seen on a phone).
    if (m.hint) {
      const hint = document.createElement("dd");
      hint.className = "metric-hint";
      hint.textContent = m.hint;
      div.append(hint);
    }
    dl.append(div);
  }
  return dl;
}

function tableOf(t, group) {
  const wrap = document.createElement("div");
  wrap.className = "table-wrap";
  const table = document.createElement("table");
  table.className = "report-table";
  table.dataset.key = t.key ?? "";
  if (t.title) {
    const cap = document.createElement("caption");
    cap.textContent = t.title;
    table.append(cap);
  }
  const rows = (t.rows ?? []).filter((r) => !t.group || group === null || !Number.isInteger(r.group_index) || r.group_index === group);
  const cols = t.columns ?? [];
  if (rows.length === 1 && cols.length > 3) {
    // One row of many columns reads better transposed: a column of label / value pairs.
    table.classList.add("transposed");
    const body = document.createElement("tbody");
    cols.forEach((c, k) => {
      const tr = document.createElement("tr");
      const th = document.createElement("th");
      th.scope = "row";
      th.textContent = c.label ?? "";
      tr.append(th, cell(rows[0].cells?.[k], c.unit));
      body.append(tr);
    });
    table.append(body);
  } else {
    const head = document.createElement("thead");
    const tr = document.createElement("tr");
    for (const c of cols) {
      const th = document.createElement("th");
      th.scope = "col";
      th.textContent = axisTitle(c);
      tr.append(th);
    }
    head.append(tr);
    const body = document.createElement("tbody");
    for (const r of rows) {
      const row = document.createElement("tr");
      if (group !== null && r.group_index === group) row.className = "current";
      (r.cells ?? []).forEach((v, k) => row.append(cell(v, null, k === 0 ? "th" : "td")));
      body.append(row);
    }
    table.append(head, body);
  }
  wrap.append(table);
  return wrap;
}

function cell(v, unit, tag = "td") {
  const td = document.createElement(tag);
  td.textContent = typeof v === "number" ? formatNumber(v, 4) : String(v ?? "–");
  if (typeof v === "number") td.className = "num";
  if (unit) {
    const u = document.createElement("span");
    u.className = "unit";
    u.textContent = ` ${unit}`;
    td.append(u);
  }
  return td;
}
