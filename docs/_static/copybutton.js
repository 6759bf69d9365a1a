// A "Copy" button on every code block of the site (Sphinx's Debian packages have no
// sphinx-copybutton). It copies what a reader would type: in a ```console block the lines that
// start with "$ " (without it), in every other block the text as shown.
(function () {
  "use strict";

  function textOf(block) {
    const pre = block.querySelector("pre");
    const text = pre ? pre.innerText : block.innerText;
    if (!block.closest(".highlight-console")) return text.replace(/\n$/, "");
    const commands = [];
    let continued = false;
    for (const line of text.split("\n")) {
      if (line.startsWith("$ ")) commands.push(line.slice(2));
      else if (continued) commands.push(line);
      else continue;
      continued = line.endsWith("\\");
    }
    return commands.length ? commands.join("\n") : text.replace(/\n$/, "");
  }

  function copy(text) {
    if (navigator.clipboard && window.isSecureContext) return navigator.clipboard.writeText(text);
    // file:// pages and plain HTTP: a hidden text area and the older copy command.
    return new Promise(function (resolve, reject) {
      const area = document.createElement("textarea");
      area.value = text;
      area.setAttribute("readonly", "");
      area.style.position = "fixed";
      area.style.opacity = "0";
      document.body.appendChild(area);
      area.select();
      const ok = document.execCommand("copy");
      document.body.removeChild(area);
      ok ? resolve() : reject(new Error("copy refused"));
    });
  }

  function addButtons() {
    document.querySelectorAll("div.highlight").forEach(function (block) {
      if (block.querySelector("button.kccd-copy")) return;
      const button = document.createElement("button");
      button.type = "button";
      button.className = "kccd-copy";
      button.textContent = "Copy";
      button.setAttribute("aria-label", "Copy this code");
      button.addEventListener("click", function () {
        copy(textOf(block)).then(
          function () { button.textContent = "Copied"; },
          function () { button.textContent = "Select and copy"; });
        setTimeout(function () { button.textContent = "Copy"; }, 1500);
      });
      block.appendChild(button);
    });
  }

  if (document.readyState === "loading") document.addEventListener("DOMContentLoaded", addButtons);
  else addButtons();
})();
