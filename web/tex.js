// TeX as MathML: Temml (vendored) loaded on first use, for the lessons (learn.js) and the
// model form's equations (form.js).

let temml = null;
export const loadTemml = async () => {
  temml ??= (await import('./vendor/temml/temml.mjs')).default;
  return temml;
};

// Temml writes a few inline styles, which the page's Content-Security-Policy (style-src
// 'self') refuses: they become data attributes that style.css styles the same way.
const INLINE_STYLES = { 'display:blockmath;': '', 'math-depth:0;': ' data-tml="depth0"' };
function mathml(tex, display) {
  const markup = temml.renderToString(tex, { displayMode: display, throwOnError: false });
  return markup.replace(/ style="([^"]*)"/g, (_, decl) => INLINE_STYLES[decl.replace(/\s+/g, '')] ?? '');
}

/** Text with `$…$` (inline) and `$$…$$` (displayed) TeX as DOM nodes. The lessons are the
 *  page's own static text; only Temml's MathML is parsed as markup. */
export function richText(text) {
  const nodes = [];
  for (const part of text.split(/(\$\$[^$]+\$\$|\$[^$]+\$)/)) {
    if (!part) continue;
    const display = part.startsWith('$$');
    if (part.startsWith('$')) {
      const tex = part.slice(display ? 2 : 1, display ? -2 : -1);
      const t = document.createElement('template');
      t.innerHTML = mathml(tex, display);
      nodes.push(...t.content.childNodes);
    } else {
      nodes.push(document.createTextNode(part));
    }
  }
  return nodes;
}
