window.meshcolErrors = [];
window.addEventListener("error", function (e) {
  window.meshcolErrors.push(String(e.message));
  document.title = "meshcol-error: " + e.message;
  document.documentElement.setAttribute("data-error", String(e.message));
});
(function () {  // console errors count too (a viewer that fails quietly)
  var original = console.error;
  console.error = function () {
    var text = Array.prototype.join.call(arguments, " ");
    window.meshcolErrors.push(text);
    document.documentElement.setAttribute("data-console-error", text.slice(0, 200));
    return original.apply(console, arguments);
  };
})();
