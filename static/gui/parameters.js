/* The collector's ROS parameters dialog. */
import { $ } from "./dom.js";
import { _ } from "./i18n.js";
import { ApiError } from "./api.js";
import { notice, showError } from "./feedback.js";
import { roundFloat } from "./format.js";
import { Collector } from "./collector.js";

$("#open-parameters").addEventListener("click", () => Parameters.open());

/* Rendered from the collector's parameter schema (type, bounds, choices,
 * message types); the server checks every value against the same schema. */

const Parameters = {
  input(row) {
    let input;
    if (row.type === "bool") {
      input = document.createElement("select");
      input.append(new Option("true", "true"), new Option("false", "false"));
      input.value = String(row.value);
    } else if (row.multiline) {
      input = document.createElement("textarea");
      input.rows = 6;
      input.spellcheck = false;
      input.value = row.value;
    } else if (row.choices) {
      input = document.createElement("select");
      input.append(...row.choices.map((c) => new Option(c, c)));
      input.value = row.value;
    } else {
      input = document.createElement("input");
      input.value = row.type === "float" ? roundFloat(row.value) : row.value;
      if (row.type === "int" || row.type === "float") {
        input.type = "number";
        input.step = row.type === "int" ? "1" : "any";
        if (row.minimum !== null) input.min = String(row.minimum);
        if (row.maximum !== null) input.max = String(row.maximum);
      }
      if (row.suggestions.length) {
        const list = document.createElement("datalist");
        list.id = `topics-${row.name.replace(/\W/g, "-")}`;
        list.append(...row.suggestions.map((t) => new Option(t)));
        input.setAttribute("list", list.id);
        input.after(list);
        input._list = list;
      }
    }
    input.name = row.name;
    input.setAttribute("aria-label", row.name);
    return input;
  },
  /* Puts a preset's document into the field, to be edited and applied as
   * any value is; the server checks it as it checks a typed one. */
  presetPicker(row, input) {
    const picker = document.createElement("select");
    picker.className = "preset-picker";
    picker.setAttribute("aria-label", `${row.name}: ${_("start from a preset")}`);
    picker.append(new Option(_("Start from a preset…"), ""));
    for (const preset of row.presets) {
      const option = new Option(`${preset.name}: ${preset.summary}`, preset.name);
      picker.append(option);
    }
    picker.addEventListener("change", () => {
      const preset = row.presets.find((p) => p.name === picker.value);
      if (preset) input.value = preset.document;
      picker.value = "";
      input.focus();
    });
    return picker;
  },
  read(row, input) {
    if (row.type === "bool") return input.value === "true";
    if (row.type === "int") return Number.parseInt(input.value, 10);
    // An untouched float keeps its exact value, not the rounded one shown.
    if (row.type === "float") return input.value === String(roundFloat(row.value)) ? row.value : Number.parseFloat(input.value);
    return input.value;
  },
  open() {
    const d = $("#parameters-dialog");
    const body = $(".parameters-body", d);
    const errorBox = $(".dialog-error", d);
    errorBox.hidden = true;
    const rows = (Collector.status && Collector.status.parameters) || [];
    const table = document.createElement("table");
    table.className = "params";
    const inputs = new Map();
    for (const row of rows) {
      const tr = document.createElement("tr");
      const name = document.createElement("td");
      name.textContent = row.name;
      name.title = row.description;
      const cell = document.createElement("td");
      const input = this.input(row);
      if (row.presets && row.presets.length) cell.append(this.presetPicker(row, input));
      cell.append(input);
      if (input._list) cell.append(input._list);
      const help = document.createElement("td");
      help.className = "muted";
      help.textContent = row.expects.length ? row.expects.join(", ") : row.description;
      tr.append(name, cell, help);
      table.append(tr);
      inputs.set(row.name, [row, input]);
    }
    const apply = document.createElement("button");
    apply.type = "button";
    apply.className = "primary";
    apply.textContent = _("Apply");
    apply.addEventListener("click", async () => {
      errorBox.hidden = true;
      const changes = {};
      for (const [name, [row, input]] of inputs) {
        const value = this.read(row, input);
        if (value !== row.value) changes[name] = value;
      }
      if (!Object.keys(changes).length) return showError(new ApiError(_("Nothing was changed.")), errorBox);
      // The robot's answer replaces this toast; it may come before the request's own reply.
      notice(_("Sending the parameters to the robot…"));
      try {
        await Collector.command("set_parameters", { parameters: changes });
      } catch (err) {
        showError(err, errorBox);
      }
    });
    const save = document.createElement("button");
    save.type = "button";
    save.textContent = _("Save to the node's YAML file");
    save.addEventListener("click", async () => {
      errorBox.hidden = true;
      notice(_("Asking the robot to save its parameters…"));
      try {
        await Collector.command("save_parameters");
      } catch (err) {
        showError(err, errorBox);
      }
    });
    const buttons = document.createElement("div");
    buttons.className = "buttons";
    buttons.append(apply, save);
    const empty = document.createElement("p");
    empty.textContent = _("The collector has not reported its parameters yet.");
    body.replaceChildren(rows.length ? table : empty, buttons);
    $(".close", d).onclick = () => d.close();
    d.showModal();
  },
};
