// flipstudy web: the study's timeline on jsPsych (config in config.js, written by
// `flipstudy export-web`).  The screens are the local page's (instructions,
// demographics, examples of correct motions, trials with breaks, the end), built from
// jsPsych's own plugins: instructions, survey-html-form, preload, html-keyboard-response,
// video-button-response, html-button-response.
//
// Names.  The exported site knows its videos and groups by opaque names only (keyed hashes;
// the map stays in the study, STUDY/web/site-map.json): a record names a trial's video and
// group by them and carries no clip, kind or level; import-web maps them back.  The local
// runner's page too: the server sends its screens and videos by the same names and maps each
// answer's video back to its stimulus.
//
// Data.  Every record (start, demographics, answer, end) is one flat JSON object.  It is
// checkpointed in localStorage at once, then sent to the host the site was exported for:
//   jatos     jatos.appendResultData(record as one JSON line), in order, retried
//   pavlovia  the whole record list so far as CSV, under one file name per run
//             (Pavlovia's experiment API: open a session, POST results, DELETE at the end)
//   static    nothing is sent; the end screen offers the records as a download
// The end screen always offers the download (a .jsonl file), on every host.  A reload
// resumes at the first unanswered trial: the order is recomputed from the participant ID
// (flipstudy-order.js) and the answers so far are read back from localStorage.
//
// Playback.  Each video is loaded completely (preload plugin: a Blob) before its trial.
// While it plays, requestVideoFrameCallback counts the frames presented (metadata
// presentedFrames; without the API, a requestAnimationFrame loop counts the distinct
// frames of currentTime); frames_dropped = the video's frames - frames presented;
// playback_ms (first frame to 'ended') is recorded beside video_ms, and the display's
// refresh rate is measured once at the start (median requestAnimationFrame interval).
// A trial whose dropped frames exceed max_dropped_pct % of the video's is flagged.
//
// Repeats.  With repeat_dropped (the design's [session] repeat_dropped), every trial
// whose answer was flagged is shown once more after the last trial, in the trials'
// order, at most once each; its record is a second answer with repeat = 1 (the first
// answer, repeat = 0, is kept as it was).  Which are due is read from the checkpoint, so
// a reload during the repeats resumes at the first one not yet answered.
'use strict';
(function () {
  const C = window.FLIPSTUDY;
  const ORDER = window.FlipstudyOrder;
  const FORMAT = 'flipstudy-web/1';
  const app = () => document.getElementById('jspsych-target');
  const esc = (s) => String(s).replace(/[&<>"']/g, (c) => ({'&': '&amp;', '<': '&lt;', '>': '&gt;', '"': '&quot;', "'": '&#39;'}[c]));
  const round1 = (x) => Math.round(x * 10) / 10;
  const nowIso = () => new Date().toISOString();
  const sleep = (ms) => new Promise((r) => setTimeout(r, ms));
  // not starting with '-': a spreadsheet reads a leading '-' as a formula (import-web refuses it too)
  const PID_RE = /^[A-Za-z0-9_][A-Za-z0-9_-]{0,31}$/;
  const RECRUIT_RE = /^[A-Za-z0-9_][A-Za-z0-9_-]{0,63}$/;
  // a time as nowIso() writes it: the consent record's agreement
  const ISO_RE = /^\d{4}-\d\d-\d\dT\d\d:\d\d:\d\d(\.\d{1,9})?(Z|[+-]\d\d:?\d\d)?$/;

  function setScreen(id, type) {
    const el = app();
    el.dataset.screenId = id;
    el.dataset.screen = type;
  }

  // ---- participant and checkpoint ----------------------------------------------------------
  function storage() {
    try {
      const k = '__flipstudy_probe__';
      window.localStorage.setItem(k, '1');
      window.localStorage.removeItem(k);
      return window.localStorage;
    } catch (e) { return null; }
  }
  const store = storage();

  function randomId(prefix, n) {
    const abc = 'abcdefghijkmnpqrstuvwxyz23456789';
    const b = new Uint8Array(n);
    crypto.getRandomValues(b);
    return prefix + Array.from(b, (x) => abc[x % abc.length]).join('');
  }

  function participantFrom(params) {
    for (const name of C.participant_params) {
      const v = params.get(name);
      if (v !== null && v !== '') {
        if (!PID_RE.test(v)) throw new Error(`the participant ID in the link (${name}=${v}) is not valid: use 1-32 letters, digits, '_' or '-' (not first)`);
        return {id: v, from: name};
      }
    }
    const key = `flipstudy:${C.site_id}:generated-id`;
    let id = store && store.getItem(key);
    if (!id) {
      id = randomId('W', 12);
      if (store) store.setItem(key, id);
    }
    return {id, from: 'generated'};
  }

  class Checkpoint {
    constructor(participant) {
      this.key = `flipstudy:${C.site_id}:${participant}`;
      let s = null;
      try { s = store && JSON.parse(store.getItem(this.key) || 'null'); } catch (e) { s = null; }
      this.s = s || {records: [], sent: 0};
    }
    save() {
      if (!store) return;
      try { store.setItem(this.key, JSON.stringify(this.s)); } catch (e) { console.error('flipstudy: checkpoint not saved', e); }
    }
    get records() { return this.s.records; }
    answers() { return this.s.records.filter((r) => r.record === 'answer'); }
    // the answers of the trial order (repeat 0) and the repeats of flagged ones (repeat 1)
    firsts() { return this.answers().filter((r) => !r.repeat); }
    repeats() { return this.answers().filter((r) => r.repeat); }
    has(kind) { return this.s.records.some((r) => r.record === kind); }
  }

  // ---- hosts: where records go besides the browser ------------------------------------------
  function csvOf(records) {
    const cols = [];
    for (const r of records) for (const k of Object.keys(r)) if (!cols.includes(k)) cols.push(k);
    const cell = (v) => {
      if (v === null || v === undefined) return '';
      const s = typeof v === 'string' ? v : JSON.stringify(v);
      return /[",\n\r]/.test(s) ? '"' + s.replace(/"/g, '""') + '"' : s;
    };
    return [cols.join(',')].concat(records.map((r) => cols.map((c) => cell(r[c])).join(','))).join('\n') + '\n';
  }

  const hosts = {};
  hosts.static = {
    async init() {}, async send() {}, async finish() {},
  };
  hosts.jatos = {
    async init() {
      if (typeof jatos === 'undefined') throw new Error('jatos.js is not loaded: run this site as a JATOS study component');
      await new Promise((resolve) => jatos.onLoad(resolve));
    },
    params() { return new URLSearchParams(jatos.urlQueryParameters || {}); },
    async send(cp) {
      // one JSON line per record, in order; `sent` counts what JATOS has acknowledged
      while (cp.s.sent < cp.records.length) {
        await jatos.appendResultData(JSON.stringify(cp.records[cp.s.sent]) + '\n');
        cp.s.sent += 1;
        cp.save();
      }
    },
    // least-filled first through JATOS's batch session (shared by every run of the batch):
    // the counts are read, the smallest taken, and the set retried when another run wrote first
    async assign(between, key = 'flipstudy-conditions') {
      for (let i = 0; i < 50; i++) {
        const counts = Object.assign({}, jatos.batchSession.get(key) || {});
        let best = between[0];
        for (const c of between) if ((counts[c] || 0) < (counts[best] || 0)) best = c;
        counts[best] = (counts[best] || 0) + 1;
        try { await jatos.batchSession.set(key, counts); return best; } catch (e) { await sleep(50 + 200 * Math.random()); }
      }
      throw new Error('JATOS batch session: no condition could be assigned');
    },
    async finish(cp, answered) {
      if (typeof jatos.endStudyAjax === 'function') await jatos.endStudyAjax(true, `flipstudy: ${answered} answers`);
    },
  };
  hosts.pavlovia = {
    async init(cp, participant) {
      const cfg = await (await fetch('config.json', {cache: 'no-cache'})).json();
      this.cfg = cfg;
      this.base = `${cfg.pavlovia.URL}/api/v2/experiments/${cfg.gitlab.projectId}/sessions`;
      const pilot = new URLSearchParams(location.search).get('__pilotToken');
      const form = new FormData();
      if (pilot) form.append('pilotToken', pilot);
      const r = await (await fetch(this.base, {method: 'POST', body: form, credentials: 'same-origin'})).json();
      if (!r.token) throw new Error('Pavlovia did not open a session (no token)');
      this.token = r.token;
      this.running = r.experiment && r.experiment.status2 === 'RUNNING' && !pilot;
      this.key = `${cfg.experiment.name}_${participant}_${cp.s.run_id}.csv`;
    },
    async send(cp) {
      if (!this.running) return;                          // piloting: the download only
      const n = cp.records.length;
      if (cp.s.sent >= n) return;
      const form = new FormData();
      form.append('key', this.key);
      form.append('value', csvOf(cp.records));
      const r = await fetch(`${this.base}/${this.token}/results`, {method: 'POST', body: form, credentials: 'same-origin'});
      if (!r.ok) throw new Error(`Pavlovia answered ${r.status}`);
      cp.s.sent = n;
      cp.save();
    },
    async finish(cp) {
      const form = new FormData();
      form.append('isCompleted', 'true');
      await fetch(`${this.base}/${this.token}`, {method: 'DELETE', body: form, credentials: 'same-origin'});
    },
  };

  // a single sender: records go out in order, one request at a time, retried with backoff
  function makeSender(host, cp) {
    let running = null;
    let wait = 500;
    const state = {failures: 0};                       // failed sends in a row (the end screen reads it)
    const loop = async () => {
      for (;;) {
        try {
          await host.send(cp);
          wait = 500;
          state.failures = 0;
          if (cp.s.sent >= cp.records.length || C.host === 'static') return;
        } catch (e) {
          state.failures += 1;
          console.warn('flipstudy: sending failed, retrying', e);
          await sleep(wait);
          wait = Math.min(wait * 2, 8000);
        }
      }
    };
    return {
      state,
      kick() { if (!running) running = loop().finally(() => { running = null; }); return running; },
      async flush() { while (C.host !== 'static' && cp.s.sent < cp.records.length) { await this.kick(); } },
    };
  }

  // ---- playback measurement ---------------------------------------------------------------
  function measureRefresh(ms) {
    return new Promise((resolve) => {
      const t = [];
      const t0 = performance.now();
      const tick = (ts) => {
        t.push(ts);
        if (ts - t0 < ms || t.length < 10) requestAnimationFrame(tick);
        else {
          const d = t.slice(1).map((x, i) => x - t[i]).sort((a, b) => a - b);
          const med = d[Math.floor(d.length / 2)];
          resolve(med > 0 ? round1(1000 / med) : null);
        }
      };
      requestAnimationFrame(tick);
      setTimeout(() => resolve(null), ms + 3000);       // a hidden tab runs no frames
    });
  }

  // Answer keys of a two-button question: key0 / key1 click button 0 / 1 once it is enabled
  // (the yes/no trial's F/J and the 2AFC question's F/J); onKeyInput runs first.
  function answerKeys(buttons, key0, key1, onKeyInput) {
    return (e) => {
      if (e.repeat || e.ctrlKey || e.metaKey || e.altKey) return;
      const k = (e.key || '').toLowerCase();
      const i = k === key0 ? 0 : k === key1 ? 1 : -1;
      if (i < 0 || buttons[i].disabled) return;
      onKeyInput();
      buttons[i].click();
    };
  }

  function watchPlayback(video, info) {
    const m = {timing: null, first: null, last: null, seen: new Set(), tFirst: null, tPlaying: null, tEnded: null, done: false};
    const fps = info.fps;
    if (typeof video.requestVideoFrameCallback === 'function') {
      m.timing = 'rvfc';
      const cb = (now, md) => {
        if (m.done) return;
        if (m.first === null) { m.first = md.presentedFrames; m.tFirst = md.expectedDisplayTime || now; }
        m.last = md.presentedFrames;
        m.seen.add(Math.round(md.mediaTime * fps));
        video.requestVideoFrameCallback(cb);
      };
      video.requestVideoFrameCallback(cb);
    } else {
      m.timing = 'raf';
      const tick = (ts) => {
        if (m.done) return;
        if (!video.paused && video.currentTime > 0) {
          if (m.tFirst === null) m.tFirst = ts;
          m.seen.add(Math.floor(video.currentTime * fps + 1e-6));
        }
        requestAnimationFrame(tick);
      };
      requestAnimationFrame(tick);
    }
    video.addEventListener('playing', () => { if (m.tPlaying === null) m.tPlaying = performance.now(); });
    video.addEventListener('ended', () => {
      if (m.tEnded === null) m.tEnded = performance.now();
      m.done = true;
    }, {once: true});
    m.result = () => {
      if (m.tEnded === null) m.tEnded = performance.now();
      const expected = info.frames;
      const presented = m.timing === 'rvfc' && m.first !== null ? Math.min(expected, m.last - m.first + 1)
        : Math.min(expected, m.seen.size);
      const dropped = Math.max(0, expected - presented);
      const pct = expected > 0 ? 100 * dropped / expected : 0;
      return {
        shown_ms: m.tPlaying === null ? 0 : round1(m.tEnded - m.tPlaying),
        frames_expected: expected, frames_presented: presented, frames_dropped: dropped,
        frames_seen: m.seen.size, dropped_pct: round1(pct),
        playback_ms: m.tFirst === null ? 0 : round1(m.tEnded - m.tFirst),
        video_ms: round1((isFinite(video.duration) ? video.duration : info.duration_s) * 1000),
        timing: m.timing, playback_flagged: pct > C.max_dropped_pct,
      };
    };
    return m;
  }

  // ---- screens -----------------------------------------------------------------------------
  function card(title, paragraphs, extra = '') {
    return `<div class="fs-card"><h1>${esc(title)}</h1>${paragraphs.map((p) => `<p>${esc(p)}</p>`).join('')}${extra}</div>`;
  }

  // which tone is the left side: the sentence and the picture of config.sides (left and
  // right limbs differ only by tone)
  function sidesHtml() {
    const S = C.sides;
    if (!S) return '';
    const img = S.image ? `<img src="${S.image}" alt="${esc(S.alt)}" width="${S.width}" height="${S.height}">` : '';
    return `<figure class="fs-sides">${img}<figcaption>${esc(S.text)}</figcaption></figure>`;
  }

  function demographicsHtml(fields) {
    const parts = [];
    for (const f of fields) {
      if (f.kind === 'number') {
        parts.push(`<div class="fs-field"><label for="fs-${f.name}">${esc(f.label)}</label>
          <div class="fs-choices"><input type="number" id="fs-${f.name}" name="${f.name}" min="${f.min}" max="${f.max}" step="1" required>
          <label><input type="checkbox" id="fs-${f.name}-none" name="${f.name}_none" value="1"> Prefer not to say</label></div></div>`);
      } else {
        const opts = f.options.map(([v, label], i) =>
          `<label><input type="radio" name="${f.name}" value="${esc(v)}"${i === 0 ? ' required' : ''}> ${esc(label)}</label>`).join(' ');
        parts.push(`<fieldset class="fs-field"><legend>${esc(f.label)}</legend><div class="fs-choices">${opts}</div></fieldset>`);
      }
    }
    return parts.join('');
  }

  function buttonHtml(cls, key) {
    return (choice) => `<button class="jspsych-btn fs-${cls(choice)}">${esc(choice)}${key(choice) ? ` <kbd>${esc(key(choice).toUpperCase())}</kbd>` : ''}</button>`;
  }

  // ---- nodes shared by every host ------------------------------------------------------------
  // env: {jsPsych, n, refresh, record(rec) (may return a Promise: the trial ends once it
  // resolves), fetchVideos(urls) (optional, the local runner: load them into jsPsych's video
  // buffers, retrying while the server is unreachable; without it jsPsych's preload plugin)}

  // A screen that stays until work() resolves (its failure stops the page with the message).
  function waitNode(env, message, screenId, work) {
    return {type: jsPsychHtmlKeyboardResponse, stimulus: message, choices: 'NO_KEYS',
      on_load: () => {
        if (screenId) setScreen(screenId, 'loading');
        work().then(() => env.jsPsych.finishTrial(), fatal);
      }};
  }

  // load `videos` (a list, or a function giving it when the screen starts) completely
  function loadNode(env, videos, message, screenId) {
    const list = () => (typeof videos === 'function' ? videos() : videos);
    if (env.fetchVideos) return waitNode(env, message, screenId, () => env.fetchVideos(list()));
    return {type: jsPsychPreload, video: list, auto_preload: false, show_progress_bar: false, message,
            continue_after_error: false, on_start: () => { if (screenId) setScreen(screenId, 'loading'); }};
  }

  function instructionsNode(id, title, paragraphs, button) {
    if (id === 'instructions') {
      return {type: jsPsychInstructions, pages: [card(title, paragraphs, sidesHtml())], show_clickable_nav: true, allow_keys: false, allow_backward: false,
              button_label_next: button || 'Continue', on_load: () => setScreen('instructions', 'instructions')};
    }
    return {type: jsPsychHtmlButtonResponse, choices: [button || 'Continue'], stimulus: card(title, paragraphs),
            on_load: () => setScreen(id, 'instructions')};
  }

  function demographicsNode(title, text, env) {
    return {type: jsPsychSurveyHtmlForm,
      preamble: `<div class="fs-card"><h1>${esc(title)}</h1><p class="fs-muted">${esc(text)}</p></div>`,
      html: demographicsHtml(C.demographic_fields), button_label: 'Continue',
      on_load: () => {
        setScreen('demographics', 'demographics');
        for (const f of C.demographic_fields.filter((x) => x.kind === 'number')) {
          const input = document.getElementById(`fs-${f.name}`);
          const none = document.getElementById(`fs-${f.name}-none`);
          none.addEventListener('change', () => { input.disabled = none.checked; input.required = !none.checked; if (none.checked) input.value = ''; });
        }
      },
      on_finish: (data) => {
        const r = data.response || {};
        const rec = {record: 'demographics'};
        for (const f of C.demographic_fields) {
          if (f.kind === 'number') rec[f.name] = r[`${f.name}_none`] ? null : Number(r[f.name]);
          else rec[f.name] = r[f.name];
        }
        return env.record(rec);
      }};
  }

  // the examples of correct motions: `videos` (URLs), each loaded, played, watched again on request
  function exampleNodes(videos, env) {
    const tl = [];
    videos.forEach((video, i) => {
      const last = i === videos.length - 1;
      tl.push(loadNode(env, [video], '<p class="fs-muted">Loading…</p>', null));
      tl.push({timeline: [{type: jsPsychVideoButtonResponse, stimulus: [video],
        choices: ['Watch again', last ? C.texts.examples_button : 'Next example'],
        button_html: buttonHtml((c) => (c === 'Watch again' ? 'again' : 'next'), () => null),
        prompt: `<p class="fs-progress">${esc(C.texts.examples_title)} · Correct motion ${i + 1} of ${videos.length}</p>
                 <p class="fs-prompt">This is a physically correct motion.</p><p class="fs-muted">${esc(C.texts.examples_text)}</p>`,
        response_allowed_while_playing: false, trial_ends_after_video: false, autoplay: true, controls: false,
        width: C.video_width, on_load: () => {
          setScreen(`example-${i + 1}`, 'examples');
          const v = document.getElementById('jspsych-video-button-response-stimulus');
          v.muted = true;
          arrange(v, document.getElementById('jspsych-video-button-response-btngroup'));
        }}],
        loop_function: (data) => data.values()[0].response === 0});
    });
    return tl;
  }

  function breakNode(id, title, text) {
    return {type: jsPsychHtmlButtonResponse, choices: ['Continue'], stimulus: card(title, [text]),
            on_load: () => setScreen(id, 'break')};
  }

  // The prompt of a video-button-response trial comes after its buttons: the progress line
  // goes above the video, the question between the video and the buttons.
  function arrange(video, group) {
    const root = group.parentNode;
    const progress = root.querySelector(':scope > .fs-progress');
    if (progress) root.insertBefore(progress, video.parentNode);
    root.querySelectorAll(':scope > .fs-prompt, :scope > .fs-muted').forEach((p) => root.insertBefore(p, group));
  }

  // A yes/no or 2AFC trial.  `t` may be filled only when the trial starts (a QUEST+ trial
  // of the local runner, served by the server): everything read from it is read late.
  function trialNodes(t, repeat, env) {
    const jsPsych = env.jsPsych;
    if (t.task === '2afc') {
      return window.Flipstudy2afc.nodes(t, repeat, {C, jsPsych, esc, setScreen, watchPlayback, answerKeys, arrange,
                                                    loadNode: (videos, message, id) => loadNode(env, videos, message, id),
                                                    record: env.record, refresh: env.refresh, n: env.n, app});
    }
    const keys = C.keys;
    const info = () => C.videos[t.stimulus];
    const sid = repeat ? `repeat-${t.trial}` : `trial-${t.trial}`;
    const progress = repeat ? `Once more: motion ${t.trial} of ${env.n}` : `Motion ${t.trial} of ${env.n}`;
    let watch = null, input = 'click', tEnabled = null, onKey = null, replays = 0;
    const fix = `<div class="fs-stage"><div class="fs-fixation">+</div></div>`;
    return [
      loadNode(env, () => [info().video], fix, `load-${sid}`),
      {type: jsPsychHtmlKeyboardResponse, stimulus: fix, choices: 'NO_KEYS', trial_duration: C.iti_ms,
       on_load: () => setScreen(`iti-${sid}`, 'iti')},
      {type: jsPsychVideoButtonResponse, stimulus: () => [info().video], choices: ['Correct', 'Incorrect'],
       button_html: buttonHtml((c) => c.toLowerCase(), (c) => keys[c.toLowerCase()]),
       prompt: `<p class="fs-progress"><span>${esc(progress)}</span><span>${esc(keys.correct.toUpperCase())} = correct · ${esc(keys.incorrect.toUpperCase())} = incorrect</span></p>
                <p class="fs-prompt">${esc(C.texts.prompt)}</p>`,
       response_allowed_while_playing: false, trial_ends_after_video: false, autoplay: true, controls: false,
       width: C.video_width,
       on_load: () => {
         setScreen(sid, 'trial');
         const el = app();
         el.dataset.trial = String(t.trial);
         el.dataset.stimulus = t.stimulus;
         el.dataset.playing = '1';
         const v = document.getElementById('jspsych-video-button-response-stimulus');
         v.muted = true;
         v.setAttribute('playsinline', '');
         v.disablePictureInPicture = true;
         watch = watchPlayback(v, info());
         const group = document.getElementById('jspsych-video-button-response-btngroup');
         arrange(v, group);
         const buttons = group.querySelectorAll('button');
         let bR = null;
         if (C.replay) {
           bR = document.createElement('button');
           bR.className = 'jspsych-btn fs-replay';
           bR.textContent = 'Replay';
           bR.disabled = true;
           group.appendChild(bR);
           bR.addEventListener('click', () => {
             replays += 1;
             buttons.forEach((b) => b.setAttribute('disabled', 'disabled'));
             bR.disabled = true;
             el.dataset.playing = '1';
             v.style.visibility = 'visible';
             v.currentTime = 0;
             v.play();
           });
         }
         v.addEventListener('ended', () => {
           el.dataset.playing = '0';
           v.style.visibility = 'hidden';                 // a blank stage while answering
           if (tEnabled === null) tEnabled = performance.now();
           if (bR) { bR.disabled = false; buttons.forEach((b) => b.removeAttribute('disabled')); }
         });
         onKey = answerKeys(buttons, keys.correct, keys.incorrect, () => { input = 'key'; });
         document.addEventListener('keydown', onKey);
       },
       on_finish: (data) => {
         document.removeEventListener('keydown', onKey);
         const tAnswer = performance.now();
         const pb = watch.result();
         const vb = jsPsych.pluginAPI.video_buffers;
         if (vb && vb[info().video]) { URL.revokeObjectURL(vb[info().video]); delete vb[info().video]; }
         return env.record(Object.assign({record: 'answer', trial: t.trial, stimulus: t.stimulus, group: t.group,
           repetition: t.repetition, response: data.response === 0 ? 'correct' : 'incorrect',
           rt_ms: round1(tAnswer - (tEnabled === null ? tAnswer : tEnabled)), input, replays, repeat,
           refresh_hz: env.refresh, max_dropped_pct: C.max_dropped_pct}, pb));
       }},
    ];
  }

  // ---- consent and the screen check (plain pages before jsPsych's timeline: nothing is
  // recorded before consent is given) ------------------------------------------------------
  function consentScreen(html) {
    return new Promise((resolve) => {
      setScreen('consent', 'consent');
      app().innerHTML = `<div class="fs-card fs-consent">${/^\s*<h[1-6]>/.test(html) ? '' : '<h1>Consent</h1>'}<div class="fs-consent-text">${html}</div>
        <div class="fs-actions"><button id="fs-consent-no" class="jspsych-btn">I do not agree</button>
        <button id="fs-consent-yes" class="jspsych-btn fs-next">I agree to take part</button></div></div>`;
      document.getElementById('fs-consent-yes').addEventListener('click', () => { app().innerHTML = ''; resolve(true); });
      document.getElementById('fs-consent-no').addEventListener('click', () => resolve(false));
    });
  }

  // the display against the design's minimums (refresh rate, window size in CSS pixels)
  function screenCheck(refresh, O) {
    const w = window.innerWidth, h = window.innerHeight;
    const slow = O.min_refresh_hz > 0 && !(refresh >= O.min_refresh_hz);
    const small = w < (O.min_width || 0) || h < (O.min_height || 0);
    return {ok: !slow && !small, slow, small, window: `${w}x${h}`, refresh};
  }

  function screenTooSmall(sc, O) {
    return new Promise((resolve) => {
      setScreen('screen-check', 'screen-check');
      const why = [];
      if (sc.small) why.push(`This study needs a browser window of at least ${O.min_width} × ${O.min_height} pixels; yours is ${sc.window.replace('x', ' × ')}. Please make the window larger (or use a larger screen).`);
      if (sc.slow) why.push(`This study needs a display refreshing at least ${O.min_refresh_hz} times a second; yours measured ${sc.refresh === null ? 'unknown' : sc.refresh + ' Hz'}. Please use another computer or display.`);
      app().innerHTML = card('Your screen', why.concat(['Press "Check again" when you have changed it.'])) +
        '<div class="fs-actions"><button id="fs-check-again" class="jspsych-btn fs-next">Check again</button></div>';
      document.getElementById('fs-check-again').addEventListener('click', () => { app().innerHTML = ''; resolve(); });
    });
  }

  // ---- the exported site (static, jatos, pavlovia): the order and the records are the browser's
  function startedHere(r, pid, runId, O) {
    return !!r && r.record === 'start' && r.format === FORMAT && r.site_id === C.site_id && r.participant === pid &&
      typeof runId === 'string' && r.run_id === runId && (!O.consent_html || (typeof r.consent === 'string' && ISO_RE.test(r.consent)));
  }

  async function runWeb(jsPsych) {
    const host = hosts[C.host];
    if (!host) throw new Error(`unknown host ${C.host}`);
    if (C.host === 'jatos') await host.init();
    const params = C.host === 'jatos' ? host.params() : new URLSearchParams(location.search);
    const O = C.online || {};
    const who = participantFrom(params);
    const pid = who.id;
    // the recruiter's URL parameters (Prolific's PROLIFIC_PID, STUDY_ID, SESSION_ID, ...),
    // checked as the participant ID is, and kept on every record
    const recruit = {};
    for (const name of O.recruit_params || []) {
      const v = params.get(name);
      if (v === null || v === '') continue;
      if (!RECRUIT_RE.test(v)) throw new Error(`the link's ${name}=${v} is not valid: use 1-64 letters, digits, '_' or '-' (not first)`);
      recruit[name] = v;
    }
    const cp = new Checkpoint(pid);
    // a run resumes only from the start record this site wrote for this participant and run,
    // with the agreement to the consent text on it (consent as data, checked on every load):
    // saved records without one are not a run: they are dropped with the state kept beside them
    // (run id, condition), and the run starts afresh at the consent screen
    const fresh = !cp.records.some((r) => startedHere(r, pid, cp.s.run_id, O));
    if (fresh && cp.records.length) {
      cp.s = {records: [], sent: 0};
      cp.save();
    }
    // consent first: nothing is kept or sent before it is given
    let consent = null;
    if (fresh && O.consent_html) {
      if (!(await consentScreen(O.consent_html))) {
        setScreen('no-consent', 'end');
        app().innerHTML = card('Thank you', ['You did not consent, so the study ends here. Nothing was recorded. You may close this page' +
          (O.redirect_url ? ' and return your submission on the recruiting site.' : '.')]);
        return;
      }
      consent = nowIso();
    }
    if (!cp.s.run_id) {
      cp.s.run_id = randomId('r', 10);
      cp.s.run_started = nowIso();
      cp.save();
    }
    if (C.host === 'pavlovia') await host.init(cp, pid);
    const sender = makeSender(host, cp);
    // between-subject condition: kept in the checkpoint, so a reload keeps it
    const between = O.between || [];
    if (between.length && !cp.s.condition) {
      cp.s.condition = host.assign ? await host.assign(between) : ORDER.conditionByHash(pid, between);
      cp.save();
    }
    if (between.length) recruit.condition = cp.s.condition;
    const groups = between.length ? ORDER.conditionGroups(C.groups, between, cp.s.condition) : C.groups;
    // the Latin-square row: least-filled first on JATOS (its batch session), else the ID's hash
    if (O.block_order === 'latin-square' && cp.s.latin_row === undefined) {
      const rows = ORDER.balancedLatinSquare(groups.length).map((_, i) => String(i));
      cp.s.latin_row = Number(host.assign ? await host.assign(rows, 'flipstudy-latin-rows') : ORDER.latinRow(pid, groups.length));
      cp.save();
    }
    if (O.block_order === 'latin-square') recruit.latin_row = cp.s.latin_row;
    const trials = ORDER.webTrialOrder(groups, C.repetitions, C.design_seed, pid, O.block_order, cp.s.latin_row);
    const n = trials.length;
    // the groups in the order their blocks come (a Latin-square row), recorded with the start
    const blockOrder = O.block_order === 'latin-square' ? [...new Set(trials.map((t) => t.group))].join(' ') : null;
    let refresh = await measureRefresh(500);
    const base = () => Object.assign({format: FORMAT, site_id: C.site_id, study: C.study, manifest_sha256: C.manifest_sha256,
      host: C.host, participant: pid, run_id: cp.s.run_id, run_started: cp.s.run_started, timestamp: nowIso()}, recruit);
    const emit = (rec) => {
      cp.records.push(Object.assign(base(), rec));
      cp.save();
      sender.kick();
    };
    const screenOk = () => screenCheck(refresh, O);
    if (fresh) {
      const sc = screenOk();
      emit({record: 'start', n_trials: n, participant_from: who.from, order_rule: ORDER.RULE,
            order: trials.map((t) => t.stimulus).join(' '), jspsych_version: jsPsych.version(),
            refresh_hz: refresh, user_agent: navigator.userAgent, consent, window: sc.window, screen_ok: sc.ok,
            block_order: blockOrder,
            screen: `${screen.width}x${screen.height}@${window.devicePixelRatio}`});
    } else {
      sender.kick();                                   // whatever the last page did not send
    }
    // the screen check: below the design's minimum the participant is told so, and may fix it
    for (let sc = screenOk(); !sc.ok; sc = screenOk()) {
      await screenTooSmall(sc, O);
      if (sc.slow) refresh = await measureRefresh(500);
    }
    window.flipstudyState = {participant: pid, trials, checkpoint: cp};   // for tests and debugging
    const env = {jsPsych, n, refresh, record: emit};

    const answered = cp.firsts().length;
    // trials flagged on their first showing and not repeated yet, in the trials' order
    const dueRepeats = () => {
      if (!C.repeat_dropped) return [];
      const flagged = new Set(cp.firsts().filter((r) => r.playback_flagged).map((r) => r.trial));
      const done = new Set(cp.repeats().map((r) => r.trial));
      return trials.filter((t) => flagged.has(t.trial) && !done.has(t.trial));
    };
    const tl = [];
    if (O.preload) {
      // every video of the session, fetched before the first trial, with a progress bar
      const all = [...new Set(C.references.map((ex) => ex.video).concat(trials.slice(answered).map((t) => C.videos[t.stimulus].video)))];
      tl.push({type: jsPsychPreload, video: all, auto_preload: false, show_progress_bar: true, continue_after_error: false,
               message: `<p class="fs-muted">Loading the ${all.length} videos of this study…</p>`,
               on_start: () => setScreen('preload', 'loading')});
    }
    if (answered === 0) {
      tl.push(instructionsNode('instructions', C.texts.instructions_title, C.texts.instructions));
      if (!cp.has('demographics') && O.demographics !== false) tl.push(demographicsNode(C.texts.demographics_title, C.texts.demographics_text, env));
      tl.push(...exampleNodes(C.references.map((ex) => ex.video), env));
    } else {
      const next = answered < n ? `The study continues with ${C.texts.noun || 'motion'} ${answered + 1} of ${n}.`
        : 'The study continues with the motions shown once more.';
      tl.push(instructionsNode('resume', 'Welcome back', [`Your first ${answered} answers are saved. ${next}`,
        C.texts.remember || 'Remember: some motions are physically correct and some are not.', C.texts.keys_sentence]));
    }
    const every = Math.max(1, C.break_every);
    for (const t of trials.slice(answered)) {
      if (t.trial > 1 && (t.trial - 1) % every === 0 && t.trial - 1 > answered) {
        tl.push(breakNode(`break-${t.trial - 1}`, 'Break',
          `Take a short rest. ${t.trial - 1} of ${n} ${C.texts.noun || 'motion'}s done. Continue when you are ready.`));
      }
      tl.push(...trialNodes(t, 0, env));
    }
    if (C.repeat_dropped) {
      let total = 0;
      tl.push({timeline: [{type: jsPsychHtmlButtonResponse, choices: ['Continue'],
                 stimulus: () => card('A few motions once more', [`${total === 1 ? 'One motion' : `${total} motions`} did not play smoothly on this computer, so ${total === 1 ? 'it is' : 'they are'} shown once more. Please answer again.`, C.texts.keys_sentence]),
                 on_load: () => setScreen('repeats', 'break')}],
               conditional_function: () => { total = dueRepeats().length; return total > 0 && cp.repeats().length === 0; }});
      for (const t of trials) {
        tl.push({timeline: trialNodes(t, 1, env), conditional_function: () => dueRepeats().some((d) => d.trial === t.trial)});
      }
    }
    const code = O.completion_code ? `<p class="fs-code">Your completion code: <strong id="fs-code">${esc(O.completion_code)}</strong></p>` : '';
    tl.push({type: jsPsychHtmlButtonResponse, choices: [],
      stimulus: `<div class="fs-card"><h1>${esc(C.texts.end_title)}</h1>${O.debrief_html ? `<div class="fs-debrief">${O.debrief_html}</div>` : ''}
                 <p id="fs-end-status">Saving your answers…</p>${code}
                 <p>${esc(C.texts.end_download)}</p>
                 <div class="fs-actions"><button id="fs-download" class="jspsych-btn fs-next">Download your answers</button>
                 ${C.host === 'jatos' ? '<button id="fs-finish" class="jspsych-btn fs-next" disabled>Finish</button>' : ''}</div></div>`,
      on_load: async () => {
        setScreen('end', 'end');
        const st = document.getElementById('fs-end-status');
        document.getElementById('fs-download').addEventListener('click', () => download(cp, pid));
        if (!cp.has('end')) emit({record: 'end', answered: cp.firsts().length, repeats: cp.repeats().length, n_trials: n});
        // the final save is retried with back-off; while it keeps failing the download is offered
        const warn = setInterval(() => {
          if (sender.state.failures >= 3) {
            st.textContent = 'Your answers could not be sent yet; we keep trying. Please download them now ' +
              'and keep the file, in case they cannot be sent. Do not close this page yet.';
            app().dataset.sendFailing = '1';
          }
        }, 250);
        await sender.flush();
        clearInterval(warn);
        delete app().dataset.sendFailing;
        let msg = C.texts.end_saved;
        if (!cp.s.finished) {
          try { await host.finish(cp, cp.firsts().length); cp.s.finished = nowIso(); cp.save(); } catch (e) { console.warn(e); }
        }
        if (C.host === 'static') msg = C.texts.end_static;
        st.textContent = msg;
        app().dataset.saved = '1';
        const fin = document.getElementById('fs-finish');
        if (O.redirect_url && C.host !== 'static') {
          // the recruiter's completion link (Prolific: ...submissions/complete?cc=CODE)
          st.textContent = `${msg} Returning you to the recruiting site…`;
          if (fin) fin.remove();
          app().dataset.redirect = O.redirect_url;
          setTimeout(() => window.location.assign(O.redirect_url), 1500);
        } else if (O.redirect_url) {
          const a = document.createElement('a');
          a.href = O.redirect_url; a.id = 'fs-complete'; a.className = 'jspsych-btn fs-next';
          a.textContent = 'Download first, then return to the recruiting site';
          st.parentNode.appendChild(a);
        }
        if (fin) { fin.disabled = false; fin.addEventListener('click', () => jatos.endStudy(true)); }
      }});
    await jsPsych.run(tl);
  }

  // ---- the local runner (flipstudy run): the server holds the session ----------------------
  // The screens, their order and every QUEST+ level come from the server (GET api/session,
  // GET api/trial/<n>); each answer is POSTed to api/answer and the page moves on only once
  // the server says it is stored.  While the server cannot be reached (a restart after a
  // crash) the request is retried and a banner says so; an error answer is shown to the
  // participant and the page stops: nothing advances as if it were stored.
  class HttpError extends Error {
    constructor(status, message) { super(message); this.status = status; }
  }

  function banner(text) {
    let b = document.getElementById('fs-banner');
    if (!b) {
      b = document.createElement('div');
      b.id = 'fs-banner';
      b.setAttribute('role', 'status');
      document.body.appendChild(b);
    }
    b.textContent = text || '';
    b.hidden = !text;
  }

  async function request(url, options, as) {
    let wait = 250;
    for (;;) {
      let resp = null;
      try { resp = await fetch(url, Object.assign({cache: 'no-store'}, options)); } catch (e) { resp = null; }
      if (resp && resp.ok) {
        let body = null;
        try { body = await (as === 'blob' ? resp.blob() : resp.json()); } catch (e) { body = null; }  // cut off
        if (body !== null) { banner(''); return body; }
        resp = null;
      }
      let msg = null;
      if (resp) {
        msg = `the study program answered HTTP ${resp.status}`;
        try { msg = (await resp.json()).error || msg; } catch (e) { /* not JSON */ }
        if (resp.status < 500 && resp.status !== 408 && resp.status !== 429) throw new HttpError(resp.status, msg);
      }
      banner(msg ? `${msg} — retrying… (your answers so far are saved)`
        : 'Connection to the study program lost — retrying… (your answers so far are saved)');
      await sleep(wait);
      wait = Math.min(wait * 2, 1500);
    }
  }
  const postJSON = (url, body) => request(url, {method: 'POST', headers: {'Content-Type': 'application/json'},
                                                body: JSON.stringify(body)});
  const nameOf = (url) => url.replace(/^.*\//, '').replace(/\.mp4$/, '');
  const siteVideo = (url) => C.videos[nameOf(url)].video;          // the server's URL as the site names it

  // videos fetched whole (retried like every request) into jsPsych's video buffers, where the
  // video plugin finds them; the next trials' videos are fetched ahead while one is answered
  function videoLoader(jsPsych) {
    const ahead = new Map();                                          // URL -> Promise<Blob>
    const get = (url) => {
      if (!ahead.has(url)) {
        const p = request(url, {}, 'blob');
        ahead.set(url, p);
        p.catch(() => ahead.delete(url));
      }
      return ahead.get(url);
    };
    return {
      async fetch(urls) {
        const vb = jsPsych.pluginAPI.video_buffers;
        for (const url of urls) {
          if (vb[url]) continue;
          const blob = await get(url);
          ahead.delete(url);
          vb[url] = URL.createObjectURL(blob);
        }
      },
      prefetch(urls) { for (const url of urls) if (!jsPsych.pluginAPI.video_buffers[url]) get(url).catch(() => {}); },
    };
  }

  // the site's trial object of a server trial screen
  function trialOf(s) {
    const t = {trial: s.trial, task: s.type === 'trial-2afc' ? '2afc' : 'yes-no', stimulus: s.stimulus || null};
    if (t.task === '2afc' && s.stimuli) t.pair = s.stimuli.slice();     // in the order shown
    return t;
  }

  async function runLocal(jsPsych) {
    const data = await request('api/session');
    const n = data.n_trials;
    // next: the server's next open trial (the first trial screen from `start` on: a resumed
    // session's, after the welcome back), then what each stored answer says
    const first = data.timeline.slice(data.start).find((x) => x.trial);
    const state = {participant: data.participant, session: data.session, next: first ? first.trial : null, stored: 0};
    window.flipstudyState = state;                                        // for tests and debugging
    const refresh = await measureRefresh(500);
    const record = async (rec) => {
      const body = {participant: state.participant, session: state.session};
      if (rec.record === 'demographics') {
        for (const f of C.demographic_fields) body[f.name] = rec[f.name];
        await postJSON('api/demographics', body);
        return;
      }
      if (rec.pair) body.stimuli = rec.pair.split(' ');                 // a 2AFC trial: its two, as shown
      else body.stimulus = rec.stimulus;
      Object.assign(body, {trial: rec.trial, response: rec.response, rt_ms: rec.rt_ms,
        shown_ms: rec.shown_ms, late_frames: rec.frames_dropped, replays: rec.replays, input: rec.input});
      const r = await postJSON('api/answer', body);
      state.next = r.next_trial;
      state.stored += 1;
      app().dataset.stored = String(state.stored);                     // for tests (no eval under the CSP)
    };
    const loader = videoLoader(jsPsych);
    // the videos of the two trials after trial k that are known before they are served
    const upcoming = (k) => data.timeline.filter((x) => (x.type === 'trial' || x.type === 'trial-2afc') && x.trial > k
      && (x.stimulus || x.stimuli)).slice(0, 2).flatMap((x) => (x.videos || [x.video]).map(siteVideo));
    let current = 0;
    const fetchVideos = async (urls) => { await loader.fetch(urls); loader.prefetch(upcoming(current)); };
    const env = {jsPsych, n, refresh, record, fetchVideos};
    // the server's next open trial: QUEST+ slots of a group that stopped early (stop_width)
    // are passed over, and so are breaks once nothing is left
    const passed = (trial) => state.next !== null && trial < state.next;
    const tl = [];
    for (const s of data.timeline.slice(data.start)) {
      if (s.type === 'instructions') tl.push(instructionsNode(s.id, s.title, s.paragraphs, s.button));
      else if (s.type === 'demographics') tl.push(demographicsNode(s.title, s.text, env));
      else if (s.type === 'examples') tl.push(...exampleNodes(s.stimuli.map((x) => siteVideo(x.video)), env));
      else if (s.type === 'break') {
        tl.push({timeline: [breakNode(s.id, s.title, s.text)], conditional_function: () => !(state.next > n)});
      } else if (s.type === 'trial' || s.type === 'trial-2afc') {
        const t = trialOf(s);
        const nodes = trialNodes(t, 0, env);
        // an adaptive trial's level is chosen by the server when it is served, just before it is shown
        nodes.unshift(waitNode(env, '<div class="fs-stage"><div class="fs-fixation">+</div></div>', `serve-trial-${s.trial}`,
          async () => {
            current = s.trial;
            if (s.adaptive && !s.stimulus && !s.stimuli) Object.assign(t, trialOf(await request(`api/trial/${s.trial}`)));
          }));
        tl.push({timeline: nodes, conditional_function: () => !passed(s.trial)});
      } else if (s.type === 'end') {
        tl.push({type: jsPsychHtmlButtonResponse, choices: [], stimulus: card(s.title, s.paragraphs),
                 on_load: () => { setScreen('end', 'end'); app().dataset.saved = '1'; }});
      } else throw new Error(`unknown screen type ${s.type}`);
    }
    await jsPsych.run(tl);
  }

  async function main() {
    const jsPsych = initJsPsych({display_element: 'jspsych-target'});
    await (C.host === 'local' ? runLocal(jsPsych) : runWeb(jsPsych));
  }

  function download(cp, pid) {
    const text = cp.records.map((r) => JSON.stringify(r)).join('\n') + '\n';
    const a = document.createElement('a');
    a.href = URL.createObjectURL(new Blob([text], {type: 'application/x-ndjson'}));
    a.download = `flipstudy-${C.study}-${pid}-${cp.s.run_id}.jsonl`;
    document.body.appendChild(a);
    a.click();
    a.remove();
  }

  function fatal(e) {
    console.error(e);
    const el = app();
    el.dataset.screen = 'error';
    el.dataset.screenId = 'error';
    const kept = C.host === 'local' ? 'Your saved answers are safe.' : 'Your saved answers are kept in this browser.';
    el.innerHTML = card('Please contact the experimenter', [`The study cannot continue on this page. ${kept}`, String(e && e.message || e)]);
  }

  window.addEventListener('load', () => { main().catch(fatal); });
})();
