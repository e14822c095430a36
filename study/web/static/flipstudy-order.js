// flipstudy web: the trial-order rule of flipstudy.study.order over sfc32, seeded by
// the participant ID.  Its Python twin is flipstudy/study/web/order.py (same names,
// line for line); the tests run this file under node and in Chromium and compare.
//
//   seed   key "flipstudy-web:<design seed>:<participant>", UTF-8; FNV-1a (32 bit) of
//          "0:"+key .. "3:"+key is sfc32's state a, b, c, d; 12 outputs discarded
//   below  floor(u * n / 2^32) for the next 32-bit output u
//   shuffle Fisher-Yates from the last element down, j = below(i + 1)
//   sample  k of 0..n-1: the first k places of a partial Fisher-Yates, j = i + below(n - i)
//   random  u / 2^32 for the next output u
//   2AFC    after the last block, balanceFirst (flipstudy.study.order.balance_first): in each
//           2AFC group half the trials show the original first, half the modified motion
//           (an odd one drawn with random() < 0.5), shuffled, in the trials' order
'use strict';
(function (root) {
  const RULE = 'flipstudy-web-order/1 (sfc32 seeded by FNV-1a; the rule of flipstudy.study.order)';

  function fnv1a32(bytes) {
    let h = 0x811c9dc5;
    for (const b of bytes) h = Math.imul(h ^ b, 0x01000193) >>> 0;
    return h >>> 0;
  }

  function utf8(s) { return new TextEncoder().encode(s); }

  function orderKey(designSeed, participant) { return `flipstudy-web:${designSeed}:${participant}`; }

  class Sfc32 {
    constructor(a, b, c, d) { this.a = a >>> 0; this.b = b >>> 0; this.c = c >>> 0; this.d = d >>> 0; }
    static fromKey(key) {
      const data = utf8(key);
      const s = [0, 1, 2, 3].map((i) => {
        const p = utf8(`${i}:`);
        const all = new Uint8Array(p.length + data.length);
        all.set(p); all.set(data, p.length);
        return fnv1a32(all);
      });
      const g = new Sfc32(s[0], s[1], s[2], s[3]);
      for (let i = 0; i < 12; i++) g.next();
      return g;
    }
    next() {
      let {a, b, c, d} = this;
      let t = (a + b) >>> 0;
      a = (b ^ (b >>> 9)) >>> 0;
      b = (c + (c << 3)) >>> 0;
      c = ((c << 21) | (c >>> 11)) >>> 0;
      d = (d + 1) >>> 0;
      t = (t + d) >>> 0;
      c = (c + t) >>> 0;
      this.a = a; this.b = b; this.c = c; this.d = d;
      return t;
    }
    below(n) { return Math.floor(this.next() * n / 4294967296); }
    random() { return this.next() / 4294967296; }
    shuffle(x) {
      for (let i = x.length - 1; i > 0; i--) {
        const j = this.below(i + 1);
        const t = x[i]; x[i] = x[j]; x[j] = t;
      }
    }
    sample(n, k) {
      const pool = Array.from({length: n}, (_, i) => i);
      for (let i = 0; i < k; i++) {
        const j = i + this.below(n - i);
        const t = pool[i]; pool[i] = pool[j]; pool[j] = t;
      }
      return pool.slice(0, k);
    }
  }

  // Williams' balanced Latin square of k blocks (k rows; 2k for an odd k: each row and its mirror)
  function balancedLatinSquare(k) {
    const step = [0];
    for (let j = 1; j < k; j++) step.push(j % 2 ? (j + 1) >> 1 : k - (j >> 1));
    const rows = [];
    for (let r = 0; r < k; r++) rows.push(step.map((s) => (r + s) % k));
    return k % 2 ? rows.concat(rows.map((row) => row.slice().reverse())) : rows;
  }
  function latinRow(participant, k) { return fnv1a32(utf8(`flipstudy-latin:${participant}`)) % balancedLatinSquare(k).length; }

  // groups: [[group, [{stimulus}, ...]], ...] (the site's config: opaque names of the groups
  // and videos, no clip, kind or level; a 2AFC row also has task and original)
  function webTrialOrder(groups, repetitions, designSeed, participant, blockOrder, row) {
    const rng = Sfc32.fromKey(orderKey(designSeed, participant));
    const nStimuli = groups.reduce((n, [, rows]) => n + rows.length, 0);
    const trials = [];
    const push = (row, g, rep) => {
      const t = {trial: trials.length + 1, stimulus: row.stimulus, group: g, repetition: rep};
      if (row.task === '2afc') Object.assign(t, {task: '2afc', first: '', original: row.original});
      trials.push(t);
    };
    if (blockOrder === 'latin-square') {
      const square = balancedLatinSquare(groups.length);
      const order = square[row === undefined || row === null ? latinRow(participant, groups.length) : row];
      for (const gi of order) {
        const [g, rows] = groups[gi];
        let items;
        for (let k = 0; k < 100; k++) {
          items = [];
          for (let rep = 1; rep <= repetitions; rep++) for (const r of rows) items.push([r, rep]);
          rng.shuffle(items);
          const seq = (trials.length ? [trials[trials.length - 1].stimulus] : []).concat(items.map(([r]) => r.stimulus));
          if (rows.length === 1 || seq.every((x, i) => i === 0 || x !== seq[i - 1])) break;
        }
        for (const [r, rep] of items) push(r, g, rep);
      }
      if (trials.some((t) => t.task === '2afc')) balanceFirst(trials, rng);
      return trials;
    }
    for (let rep = 1; rep <= repetitions; rep++) {
      let block;
      for (let k = 0; k < 100; k++) {
        block = makeBlock(groups, rng);
        if (!trials.length || nStimuli === 1 || block[0][0].stimulus !== trials[trials.length - 1].stimulus) break;
      }
      for (const [row, g] of block) push(row, g, rep);
    }
    if (trials.some((t) => t.task === '2afc')) balanceFirst(trials, rng);
    return trials;
  }

  // which motion each 2AFC trial shows first: half each way within each group
  function balanceFirst(trials, rng) {
    const byGroup = new Map();
    trials.forEach((t, i) => {
      if (t.task !== '2afc') return;
      if (!byGroup.has(t.group)) byGroup.set(t.group, []);
      byGroup.get(t.group).push(i);
    });
    for (const idx of byGroup.values()) {
      const n = idx.length;
      const firsts = [];
      for (let k = 0; k < Math.floor(n / 2); k++) firsts.push('original', 'modified');
      if (n % 2) firsts.push(rng.random() < 0.5 ? 'original' : 'modified');
      rng.shuffle(firsts);
      idx.forEach((i, k) => {
        const t = trials[i];
        t.first = firsts[k];
        t.pair = t.first === 'original' ? [t.original, t.stimulus] : [t.stimulus, t.original];   // as shown
      });
    }
  }

  function makeBlock(groups, rng) {
    const queues = [];
    for (const [g, rows0] of groups) {
      const rows = rows0.slice();
      rng.shuffle(rows);
      queues.push([g, rows]);
    }
    const R = Math.max(...queues.map(([, q]) => q.length));
    const rounds = new Map();
    for (const [g, q] of queues) {
      rounds.set(g, new Set(q.length === R ? Array.from({length: R}, (_, i) => i) : rng.sample(R, q.length)));
    }
    const byName = new Map(queues);
    const block = [];
    for (let r = 0; r < R; r++) {
      const names = queues.map(([g]) => g).filter((g) => rounds.get(g).has(r));
      rng.shuffle(names);
      for (const g of names) block.push([byName.get(g).pop(), g]);
    }
    return block;
  }

  // a between-subject condition from the participant ID alone (hosts that cannot count)
  function conditionByHash(participant, between) { return between[fnv1a32(utf8(`flipstudy-condition:${participant}`)) % between.length]; }
  function conditionGroups(groups, between, condition) { return groups.filter(([g]) => !between.includes(g) || g === condition); }

  const api = {RULE, fnv1a32, orderKey, Sfc32, webTrialOrder, balanceFirst, balancedLatinSquare, latinRow,
               conditionByHash, conditionGroups};
  if (typeof module !== 'undefined' && module.exports) module.exports = api;
  else root.FlipstudyOrder = api;
})(typeof window !== 'undefined' ? window : globalThis);
