// Renders the math Sphinx wrote (\( \) inline, \[ \] displayed, in elements of class "math") with the
// vendored KaTeX (docs/_ext/katex_math.py links this script after katex.min.js and auto-render).
// A formula KaTeX cannot parse stays as its source; auto-render reports it with console.error.
document.addEventListener("DOMContentLoaded", function () {
  var delimiters = [
    { left: "\\(", right: "\\)", display: false },
    { left: "\\[", right: "\\]", display: true },
  ];
  document.querySelectorAll(".math").forEach(function (element) {
    renderMathInElement(element, { delimiters: delimiters, throwOnError: true });
  });
});
