// The page's two DOM helpers, shared by main.js and learn.js.

export const $ = (id) => document.getElementById(id);

// Elements are built with DOM calls only: text (every user string included) goes through
// textContent/value/attributes, never through innerHTML, eval or Function (the page's
// Content-Security-Policy forbids the latter two anyway).
export const el = (tag, props = {}, ...children) => {
  const e = document.createElement(tag);
  for (const [k, v] of Object.entries(props)) {
    if (v == null || v === false) continue;
    if (k === 'dataset') Object.assign(e.dataset, v);
    else if (k in e && k !== 'list') e[k] = v;
    else e.setAttribute(k, v === true ? '' : String(v));
  }
  e.append(...children.filter((c) => c != null));
  return e;
};

// Fills a <select> with `[value, text, title?]` options.
export const fillOptions = (select, items) => select.replaceChildren(...items.map(([value, text, title]) => el('option', { value: String(value), title }, String(text))));
