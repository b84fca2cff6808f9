/* The REST API (/api/) and the GUI's own API (/gui/api/): every change goes
 * through the server, which applies the rules; errors become ApiError with
 * plain words and the server's field messages. */
import { CONFIG } from "./dom.js";
import { _ } from "./i18n.js";

export const NETWORK_MESSAGE = _("The server cannot be reached. Check the network connection and try again.");

export class ApiError extends Error {
  constructor(message, status, errors) {
    super(message);
    this.status = status;
    this.errors = errors || {};
  }
}

export function plainMessage(error) {
  if (error instanceof ApiError) return error.message;
  if (error instanceof TypeError) return NETWORK_MESSAGE;
  return _("Something went wrong: %(error)s", { error: error && error.message ? error.message : String(error) });
}

export function csrfToken() {
  const match = document.cookie.match(/(?:^|;\s*)csrftoken=([^;]+)/);
  return match ? decodeURIComponent(match[1]) : "";
}

const STATUS_WORDS = {
  401: _("You are signed out. Reload the page and sign in again."),
  403: _("Your account may not do this. Ask an administrator for the operator role."),
  404: _("This entry no longer exists; somebody may have deleted it."),
  413: _("The file is too large for the server."),
  500: _("The server failed to do this. Please try again; if it keeps failing, tell the administrator."),
  502: NETWORK_MESSAGE,
  503: NETWORK_MESSAGE,
};

/* "Text: This field may not be blank." rather than a bare message without its field. */
function describeErrors(data) {
  const parts = [];
  for (const [field, messages] of Object.entries(data.errors || {})) {
    for (const m of [].concat(messages)) {
      if (field === "non_field_errors" || field === "detail") parts.push(String(m));
      else {
        const name = field.replace(/_/g, " ");
        parts.push(`${name.charAt(0).toUpperCase()}${name.slice(1)}: ${m}`);
      }
    }
  }
  return parts.length ? parts.join(" ") : data.detail;
}

export async function api(method, path, body, { root = CONFIG.apiRoot, signal, reason } = {}) {
  const headers = { Accept: "application/json" };
  // Why a final test event is amended; the server refuses such a change without it.
  if (reason) headers["X-FTT-Change-Reason"] = reason;
  let payload;
  if (body instanceof FormData) {
    payload = body;
  } else if (body !== undefined) {
    headers["Content-Type"] = "application/json";
    payload = JSON.stringify(body);
  }
  if (method !== "GET") headers["X-CSRFToken"] = csrfToken();
  const response = await fetch(root + path, { method, headers, body: payload, credentials: "same-origin", signal });
  if (response.status === 204) return null;
  let data = null;
  const type = response.headers.get("Content-Type") || "";
  if (type.includes("json")) data = await response.json().catch(() => null);
  if (!response.ok) {
    let message = data && data.detail ? describeErrors(data) : STATUS_WORDS[response.status];
    if (!message) message = _("The server refused this (error %(status)s).", { status: response.status });
    throw new ApiError(message, response.status, data && data.errors);
  }
  return data;
}

/* A whole list: one page as long as the server allows (its pagination's limit, in the page's config). */
export async function list(path, params = {}) {
  const query = new URLSearchParams({ page_size: String(CONFIG.pageSize), ...params });
  const data = await api("GET", `${path}?${query}`);
  return Array.isArray(data) ? data : data.results;
}
