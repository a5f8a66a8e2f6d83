// MathJax configuration for pymdownx.arithmatex (generic mode), as recommended by
// mkdocs-material: render \( \) inline and \[ \] display maths, re-typeset on
// instant-navigation page changes.
window.MathJax = {
  tex: {
    inlineMath: [["\\(", "\\)"]],
    displayMath: [["\\[", "\\]"]],
    processEscapes: true,
    processEnvironments: true
  },
  options: {
    ignoreHtmlClass: ".*|",
    processHtmlClass: "arithmatex"
  }
};

// MathJax (vendored in javascripts/mathjax/) may not have loaded yet, or at all (a page
// opened from disk with scripts blocked): then there is nothing to re-typeset
if (typeof document$ !== "undefined") {
  document$.subscribe(() => {
    const mj = window.MathJax;
    if (!mj || !mj.startup || !mj.startup.output || typeof mj.typesetPromise !== "function") {
      return;
    }
    mj.startup.output.clearCache();
    mj.typesetClear();
    mj.texReset();
    mj.typesetPromise();
  });
}
