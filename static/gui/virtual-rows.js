/* A table body that holds only the rows in view (± MARGIN) once its list is
 * longer than LIMIT: the rows out of view are gaps whose height (--span rows of
 * --row px) keeps the scroll height right, and aria-rowcount / aria-rowindex
 * tell a screen reader where a row stands in the whole list.  A row keeps its
 * node while its item stays in the list (only its words are written again), so
 * a live message costs the rows it touched, however long the list.  The row
 * that has the focus stays rendered when it scrolls out of view; the arrow keys
 * move the focus along the whole list.  It shows what it is given and decides
 * nothing about the items. */

const LIMIT = 60;
const MARGIN = 20;
const KEYS = { ArrowDown: 1, ArrowUp: -1, PageDown: 10, PageUp: -10, Home: -Infinity, End: Infinity };

export class VirtualRows {
  /* build(item) -> a new <tr> showing it; update(tr, item) writes its words again. */
  constructor({ table, scroller, build, update }) {
    this.table = table;
    this.body = table.tBodies[0];
    this.scroller = scroller;
    this.build = build;
    this.update = update;
    this.items = [];
    this.index = new Map(); // item id -> position in items
    this.nodes = new Map(); // item id -> its rendered <tr>
    this.gaps = [];
    this.rowHeight = 47;
    // Where the list is scrolled and how high it is, kept as they change: read in
    // a live update they would make the browser lay the page out before its time.
    this.top = 0;
    this.height = 0;
    this.head = 0;
    this.focused = null;
    this.frame = 0;
    this.measuring = 0;
    scroller.addEventListener("scroll", () => {
      this.top = scroller.scrollTop;
      this.soon();
    });
    new ResizeObserver(() => {
      this.height = scroller.clientHeight;
      this.head = table.tHead ? table.tHead.offsetHeight : 0;
      this.soon();
    }).observe(scroller);
    this.body.addEventListener("focusin", (e) => {
      const tr = e.target.closest("tr[data-id]");
      this.focused = tr ? Number(tr.dataset.id) : null;
    });
    this.body.addEventListener("focusout", (e) => {
      if (!this.body.contains(e.relatedTarget)) this.focused = null;
    });
    scroller.addEventListener("keydown", (e) => this.key(e));
  }

  /* The list in the order shown; `changed` names the ids whose words changed
     (null: every rendered row is written again where it differs). */
  show(items, changed = null) {
    // Scrolled into the list, the row at the top stays there when rows join or leave above it.
    const top = this.top > 0 ? this.items[this.firstInView()] : undefined;
    const before = top === undefined ? undefined : this.index.get(top.id);
    this.items = items;
    this.index = new Map(items.map((item, i) => [item.id, i]));
    const after = top === undefined ? undefined : this.index.get(top.id);
    this.render(changed);
    if (before !== undefined && after !== undefined && after !== before) this.scrollTo(this.top + (after - before) * this.rowHeight);
  }

  firstInView() {
    return Math.floor(Math.max(0, this.top - this.head) / this.rowHeight);
  }

  /* Its scroll event renders the rows then in view and reads where it ended. */
  scrollTo(top) {
    this.scroller.scrollTop = top;
    this.top = Math.max(0, top);
  }

  row(id) {
    return this.nodes.get(id) || null;
  }

  /* Scrolls the list (not the page) until the row of `id` is in view. */
  reveal(id) {
    const i = this.index.get(id);
    if (i === undefined) return null;
    const head = this.table.tHead ? this.table.tHead.offsetHeight : 0;
    const { scrollTop, clientHeight } = this.scroller;
    const node = this.nodes.get(id);
    // A rendered row says where it is; another is where its gap puts it.
    const top = node ? node.offsetTop : head + i * this.rowHeight;
    const height = node ? node.offsetHeight : this.rowHeight;
    if (!clientHeight) return node || null;
    if (top - head < scrollTop) this.scrollTo(top - head);
    else if (top + height > scrollTop + clientHeight) this.scrollTo(top + height - clientHeight);
    this.render(new Set());
    return this.nodes.get(id) || null;
  }

  soon() {
    if (this.frame) return;
    this.frame = requestAnimationFrame(() => {
      this.frame = 0;
      this.render(new Set());
    });
  }

  /* Which positions are rendered: all of a short list; else the rows in view
     with MARGIN on each side, and the focused row wherever it is. */
  wanted() {
    const n = this.items.length;
    if (n <= LIMIT) return { from: 0, to: n, extra: null };
    const first = this.firstInView();
    const count = Math.ceil(this.height / this.rowHeight) + 1;
    const from = Math.max(0, Math.min(first, n - count) - MARGIN);
    const to = Math.min(n, first + count + MARGIN);
    const f = this.focused === null ? undefined : this.index.get(this.focused);
    return { from, to, extra: f !== undefined && (f < from || f >= to) ? f : null };
  }

  render(changed) {
    const { from, to, extra } = this.wanted();
    const positions = [];
    if (extra !== null && extra < from) positions.push(extra);
    for (let i = from; i < to; i++) positions.push(i);
    if (extra !== null && extra >= to) positions.push(extra);
    const hadFocus = this.body.contains(document.activeElement);
    const nodes = [];
    const kept = new Map();
    let gaps = 0;
    let built = false;
    let next = 0; // the position after the last one placed
    const gap = (span) => {
      const tr = this.gaps[gaps] || (this.gaps[gaps] = this.gapRow());
      gaps += 1;
      if (tr.style.getPropertyValue("--span") !== String(span)) tr.style.setProperty("--span", String(span));
      nodes.push(tr);
    };
    for (const i of positions) {
      if (i > next) gap(i - next);
      const item = this.items[i];
      let tr = this.nodes.get(item.id);
      if (!tr) {
        tr = this.build(item);
        built = true;
      } else if (changed === null || changed.has(item.id)) this.update(tr, item);
      const index = String(i + 2); // the header is row 1
      if (tr.getAttribute("aria-rowindex") !== index) tr.setAttribute("aria-rowindex", index);
      kept.set(item.id, tr);
      nodes.push(tr);
      next = i + 1;
    }
    if (this.items.length > next) gap(this.items.length - next);
    this.nodes = kept;
    this.place(nodes);
    const count = String(this.items.length + 1);
    if (this.table.getAttribute("aria-rowcount") !== count) this.table.setAttribute("aria-rowcount", count);
    // A focused row that left the list hands the focus to the list, never to nowhere.
    if (hadFocus && !this.body.contains(document.activeElement)) this.scroller.focus();
    if (built) this.measureSoon();
  }

  /* The body's children become `nodes` without taking out the rows that stay:
     a row taken out and put back loses the focus (and a screen reader's place). */
  place(nodes) {
    const wanted = new Set(nodes);
    for (const child of [...this.body.children]) if (!wanted.has(child)) child.remove();
    nodes.forEach((node, i) => {
      const at = this.body.children[i];
      if (at !== node) this.body.insertBefore(node, at || null);
    });
  }

  gapRow() {
    const tr = document.createElement("tr");
    tr.className = "gap";
    tr.setAttribute("aria-hidden", "true");
    const td = document.createElement("td");
    td.colSpan = this.table.tHead ? this.table.tHead.rows[0].cells.length : 1;
    tr.append(td);
    return tr;
  }

  /* The gaps are as high as the rows they stand for: the rows' height as drawn,
     read before the next frame, when the browser lays the page out anyway. */
  measureSoon() {
    if (this.measuring) return;
    this.measuring = requestAnimationFrame(() => {
      this.measuring = 0;
      this.measure();
    });
  }

  measure() {
    this.head = this.table.tHead ? this.table.tHead.offsetHeight : 0;
    if (!this.nodes.size) return;
    let sum = 0;
    for (const tr of this.nodes.values()) sum += tr.offsetHeight;
    const height = sum / this.nodes.size;
    if (!height || Math.abs(height - this.rowHeight) < 0.5) return;
    this.rowHeight = height;
    this.table.style.setProperty("--row", `${height}px`);
    this.render(new Set());
  }

  /* Arrow keys, Page Up/Down, Home and End move the focus from row to row over
     the whole list, rendering the row they reach. */
  key(e) {
    const step = KEYS[e.key];
    if (step === undefined || !this.items.length || e.altKey || e.ctrlKey || e.metaKey) return;
    const at = this.focused === null ? undefined : this.index.get(this.focused);
    let i;
    if (at === undefined) {
      i = Math.min(this.items.length - 1, this.firstInView());
      if (step === -Infinity) i = 0;
      if (step === Infinity) i = this.items.length - 1;
    } else {
      i = Math.max(0, Math.min(this.items.length - 1, at + step));
    }
    e.preventDefault();
    const tr = this.reveal(this.items[i].id);
    if (tr) tr.focus();
  }
}
