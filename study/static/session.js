// flipstudy participant page: runs a timeline of screens (data from /api/session).
// One renderer ("plugin") per screen type, jsPsych-style; no build step, no libraries.
//
// Playback: every video is fetched completely as a Blob and played from an object
// URL, so nothing buffers mid-motion.  While it plays, requestAnimationFrame
// timestamps are collected; shown_ms is the time from 'playing' to 'ended' and
// late_frames the number of frame intervals longer than 1.5x the median interval.
// rt_ms is measured from the moment the answer buttons are enabled (the end of
// the first showing) to the key press or click.
'use strict';
(() => {
  const app = document.getElementById('app');
  const banner = document.getElementById('banner');
  const blobs = new Map();          // video URL -> Promise<object URL>
  let KEYS = {correct: 'f', incorrect: 'j'};

  // ---- helpers -------------------------------------------------------------------------
  function h(tag, props, ...kids) {
    const e = document.createElement(tag);
    for (const [k, v] of Object.entries(props || {})) {
      if (k === 'class') e.className = v;
      else if (k === 'text') e.textContent = v;
      else if (k.startsWith('on')) e.addEventListener(k.slice(2), v);
      else if (v === true) e.setAttribute(k, '');
      else if (v !== false && v != null) e.setAttribute(k, String(v));
    }
    for (const c of kids) if (c != null) e.append(c);
    return e;
  }
  const show = (...nodes) => app.replaceChildren(...nodes);
  const sleep = (ms) => new Promise((r) => setTimeout(r, ms));
  const round1 = (x) => Math.round(x * 10) / 10;
  function setBanner(text) { banner.textContent = text || ''; banner.hidden = !text; }
  function clicked(button) {
    return new Promise((resolve) => button.addEventListener('click', () => resolve(), {once: true}));
  }

  class HttpError extends Error {
    constructor(status, message) { super(message); this.status = status; }
  }

  // fetch with retries while the server is unreachable (a restart resumes the session);
  // a 4xx answer is final and raises HttpError.
  async function request(url, options) {
    let wait = 250;
    for (;;) {
      let resp = null;
      try { resp = await fetch(url, Object.assign({cache: 'no-store'}, options)); } catch (e) { resp = null; }
      if (resp && resp.ok) { setBanner(''); return resp; }
      if (resp && resp.status < 500 && resp.status !== 408 && resp.status !== 429) {
        let msg = `HTTP ${resp.status}`;
        try { msg = (await resp.json()).error || msg; } catch (e) { /* not JSON */ }
        throw new HttpError(resp.status, msg);
      }
      setBanner('Connection to the study program lost — retrying… (your answers so far are saved)');
      await sleep(wait);
      wait = Math.min(wait * 2, 1500);
    }
  }
  const getJSON = async (url) => (await request(url)).json();
  const postJSON = async (url, body) => (await request(url, {
    method: 'POST', headers: {'Content-Type': 'application/json'}, body: JSON.stringify(body),
  })).json();

  // ---- video: load fully, play, measure --------------------------------------------------
  function loadVideo(url) {
    if (!blobs.has(url)) {
      const p = request(url).then((r) => r.blob()).then((b) => URL.createObjectURL(b));
      p.catch(() => blobs.delete(url));
      blobs.set(url, p);
    }
    return blobs.get(url);
  }
  async function dropVideo(url) {
    const p = blobs.get(url);
    blobs.delete(url);
    if (p) { try { URL.revokeObjectURL(await p); } catch (e) { /* already gone */ } }
  }

  function newVideo() {
    const v = h('video', {class: 'hidden', preload: 'auto', playsinline: true, disablepictureinpicture: true});
    v.muted = true;             // muted videos may start without a user gesture
    v.controls = false;
    return v;
  }

  function prepare(video, src) {
    return new Promise((resolve, reject) => {
      video.addEventListener('canplaythrough', () => resolve(), {once: true});
      video.addEventListener('error', () => reject(new Error('this video cannot be played')), {once: true});
      video.src = src;
    });
  }

  function lateFrames(stamps) {
    if (stamps.length < 3) return 0;
    const d = [];
    for (let i = 1; i < stamps.length; i++) d.push(stamps[i] - stamps[i - 1]);
    const s = d.slice().sort((a, b) => a - b);
    const n = s.length;
    const median = n % 2 ? s[(n - 1) / 2] : (s[n / 2 - 1] + s[n / 2]) / 2;
    return d.filter((x) => x > 1.5 * median).length;
  }

  // Play from the start; resolves at 'ended' with {shown_ms, late_frames, frames, stalls}.
  function playMeasured(video) {
    return new Promise((resolve, reject) => {
      const stamps = [];
      let t0 = null, done = false, stalls = 0, watchdog = null;
      const tick = (ts) => { if (!done) { stamps.push(ts); requestAnimationFrame(tick); } };
      const onPlaying = () => {
        if (t0 === null) { t0 = performance.now(); requestAnimationFrame(tick); }
      };
      const onWaiting = () => { stalls += 1; };
      const finish = () => {
        if (done) return;
        done = true;
        clearTimeout(watchdog);
        video.removeEventListener('playing', onPlaying);
        video.removeEventListener('waiting', onWaiting);
        video.removeEventListener('ended', finish);
        const t1 = performance.now();
        resolve({shown_ms: t0 === null ? 0 : t1 - t0, late_frames: lateFrames(stamps),
                 frames: stamps.length, stalls});
      };
      video.addEventListener('playing', onPlaying);
      video.addEventListener('waiting', onWaiting);
      video.addEventListener('ended', finish);
      // never leave the participant stuck if 'ended' does not come
      const limit = (isFinite(video.duration) ? video.duration * 1000 : 10000) * 2 + 5000;
      watchdog = setTimeout(() => { stalls += 1; finish(); }, limit);
      video.currentTime = 0;
      const p = video.play();
      if (p) p.catch((e) => { done = true; clearTimeout(watchdog); reject(e); });
    });
  }

  // ---- plugins: one per screen type ------------------------------------------------------
  const plugins = {};

  plugins.instructions = async (s) => {
    const btn = h('button', {class: 'primary', text: s.button || 'Continue'});
    show(h('div', {class: 'card'}, h('h1', {text: s.title}),
      ...s.paragraphs.map((p) => h('p', {text: p})), h('div', {class: 'actions'}, btn)));
    btn.focus();
    await clicked(btn);
  };

  plugins.break = async (s) => {
    const btn = h('button', {class: 'primary', text: s.button || 'Continue'});
    show(h('div', {class: 'card'}, h('h1', {text: s.title}), h('p', {text: s.text}),
      h('div', {class: 'actions'}, btn)));
    btn.focus();
    await clicked(btn);
  };

  plugins.end = async (s) => {
    show(h('div', {class: 'card'}, h('h1', {text: s.title}),
      ...s.paragraphs.map((p) => h('p', {text: p}))));
    await new Promise(() => {});     // the last screen stays
  };

  plugins.demographics = async (s, ctx) => {
    const form = h('form', {novalidate: true});
    const read = {};
    for (const f of s.fields) {
      const id = `f-${f.name}`;
      if (f.kind === 'number') {
        const input = h('input', {type: 'number', id, name: f.name, min: f.min, max: f.max, step: 1});
        const none = h('input', {type: 'checkbox', id: `${id}-none`});
        none.addEventListener('change', () => { input.disabled = none.checked; if (none.checked) input.value = ''; });
        form.append(h('div', {class: 'field'}, h('label', {for: id, text: f.label}),
          h('div', {class: 'choices'}, input,
            h('label', {}, none, ' Prefer not to say'))));
        read[f.name] = () => {
          if (none.checked) return null;
          const v = Number(input.value);
          if (input.value === '' || !Number.isInteger(v) || v < f.min || v > f.max) {
            throw new Error(`${f.label}: enter a whole number from ${f.min} to ${f.max}, or tick “Prefer not to say”.`);
          }
          return v;
        };
      } else {
        const choices = f.options.map(([value, label]) =>
          h('label', {}, h('input', {type: 'radio', name: f.name, value}), ' ', label));
        form.append(h('fieldset', {class: 'field'}, h('legend', {text: f.label}),
          h('div', {class: 'choices'}, ...choices)));
        read[f.name] = () => {
          const c = form.querySelector(`input[name="${f.name}"]:checked`);
          if (!c) throw new Error(`${f.label}: choose one (or “Prefer not to say”).`);
          return c.value;
        };
      }
    }
    const err = h('p', {class: 'error'});
    const btn = h('button', {class: 'primary', type: 'submit', text: s.button || 'Continue'});
    form.append(err, h('div', {class: 'actions'}, btn));
    show(h('div', {class: 'card'}, h('h1', {text: s.title}), h('p', {class: 'muted', text: s.text}), form));
    for (;;) {
      await new Promise((resolve) => form.addEventListener('submit', (e) => { e.preventDefault(); resolve(); }, {once: true}));
      const body = {participant: ctx.data.participant, session: ctx.data.session};
      try {
        for (const f of s.fields) body[f.name] = read[f.name]();
      } catch (e) { err.textContent = e.message; continue; }
      btn.disabled = true;
      await postJSON(s.submit, body);
      return;
    }
  };

  plugins.examples = async (s) => {
    for (let i = 0; i < s.stimuli.length; i++) {
      const ex = s.stimuli[i];
      const last = i === s.stimuli.length - 1;
      const video = newVideo();
      const again = h('button', {text: 'Watch again', disabled: true});
      const next = h('button', {class: 'primary', text: last ? s.button : 'Next example', disabled: true});
      show(h('div', {class: 'progress'}, h('span', {text: s.title}), h('span', {text: ex.label})),
        h('div', {class: 'stage'}, video, h('div', {class: 'fixation', text: 'Loading…'})),
        h('p', {class: 'prompt', text: 'This is a physically correct motion.'}),
        h('p', {class: 'muted', text: s.text}),
        h('div', {class: 'actions'}, again, next));
      if (i + 1 < s.stimuli.length) loadVideo(s.stimuli[i + 1].video);
      await prepare(video, await loadVideo(ex.video));
      app.querySelector('.fixation').classList.add('hidden');
      video.classList.remove('hidden');
      await playMeasured(video);
      for (;;) {
        again.disabled = false; next.disabled = false;
        const which = await Promise.race([clicked(again).then(() => 'again'), clicked(next).then(() => 'next')]);
        if (which === 'next') break;
        again.disabled = true; next.disabled = true;
        await playMeasured(video);
      }
      await dropVideo(ex.video);
    }
  };

  // Wait for the answer: `choices` is [[response, button, key], ...]; replay(): play the
  // motion(s) again (answers wait until it ends).  Resolves {response, input, rt_ms, replays}.
  function awaitAnswer(choices, bR, replay) {
    let replays = 0;
    const tEnabled = performance.now();
    return new Promise((resolve) => {
      let busy = false;
      const enable = (on) => { for (const [, b] of choices) b.disabled = !on; if (bR) bR.disabled = !on; };
      const finish = (response, input) => {
        if (busy) return;
        busy = true;
        document.removeEventListener('keydown', onKey);
        enable(false);
        choices.find(([r]) => r === response)[1].classList.add('chosen');
        resolve({response, input, rt_ms: performance.now() - tEnabled, replays});
      };
      const onKey = (e) => {
        if (busy || e.repeat || e.ctrlKey || e.metaKey || e.altKey) return;
        const k = (e.key || '').toLowerCase();
        const c = choices.find(([, , key]) => key === k);
        if (c) finish(c[0], 'key');
      };
      document.addEventListener('keydown', onKey);
      for (const [r, b] of choices) b.addEventListener('click', () => finish(r, 'click'));
      if (bR) {
        bR.addEventListener('click', async () => {
          if (busy) return;
          busy = true; enable(false); replays += 1;
          await replay();
          busy = false; enable(true);
        });
      }
      enable(true);
    });
  }

  // prefetch the next two trials' videos while the participant answers (an adaptive
  // trial's videos are known only when it is served)
  function prefetch(ctx) {
    ctx.data.timeline.slice(ctx.index + 1).filter((x) => x.type === 'trial' || x.type === 'trial-2afc')
      .slice(0, 2).forEach((x) => (x.videos || (x.video ? [x.video] : [])).forEach((u) => loadVideo(u)));
  }

  plugins.trial = async (s, ctx) => {
    if (document.activeElement) document.activeElement.blur();
    const video = newVideo();
    const fix = h('div', {class: 'fixation', text: '+'});
    const bC = h('button', {class: 'correct', 'data-response': 'correct', disabled: true}, 'Correct',
      h('kbd', {text: KEYS.correct.toUpperCase()}));
    const bI = h('button', {class: 'incorrect', 'data-response': 'incorrect', disabled: true}, 'Incorrect',
      h('kbd', {text: KEYS.incorrect.toUpperCase()}));
    const bR = s.replay ? h('button', {class: 'replay', text: 'Replay', disabled: true}) : null;
    show(h('div', {class: 'progress'}, h('span', {text: `Motion ${s.trial} of ${s.of}`}),
      h('span', {text: `${KEYS.correct.toUpperCase()} = correct · ${KEYS.incorrect.toUpperCase()} = incorrect`})),
    h('div', {class: 'stage'}, video, fix),
    h('p', {class: 'prompt', text: s.prompt}),
    h('div', {class: 'actions'}, bC, bI, bR));
    app.dataset.trial = String(s.trial);
    app.dataset.stimulus = s.stimulus;

    const [src] = await Promise.all([loadVideo(s.video), sleep(s.iti_ms || 0)]);
    await prepare(video, src);
    fix.classList.add('hidden');
    video.classList.remove('hidden');
    app.dataset.playing = '1';
    const m = await playMeasured(video);
    app.dataset.playing = '0';
    video.classList.add('hidden');        // a blank stage while answering
    prefetch(ctx);

    const answer = await awaitAnswer([['correct', bC, KEYS.correct], ['incorrect', bI, KEYS.incorrect]], bR,
      async () => {
        video.classList.remove('hidden');
        await playMeasured(video);
        video.classList.add('hidden');
      });
    ctx.next = (await postJSON(s.submit, {
      participant: ctx.data.participant, session: ctx.data.session, trial: s.trial,
      stimulus: s.stimulus, response: answer.response, rt_ms: round1(answer.rt_ms),
      shown_ms: round1(m.shown_ms), late_frames: m.late_frames, replays: answer.replays, input: answer.input,
    })).next_trial;
    await dropVideo(s.video);
  };

  // Two-alternative forced choice: the two motions one after the other (a label "1" / "2"
  // on the stage, a blank gap between them), then "which was physically correct?".
  // shown_ms and late_frames add up both showings.
  plugins['trial-2afc'] = async (s, ctx) => {
    if (document.activeElement) document.activeElement.blur();
    const keys = s.keys || {first: 'f', second: 'j'};
    const videos = [newVideo(), newVideo()];
    const fix = h('div', {class: 'fixation', text: '+'});
    const label = h('div', {class: 'interval hidden'});
    const bF = h('button', {class: 'first', 'data-response': 'first', disabled: true}, 'First',
      h('kbd', {text: keys.first.toUpperCase()}));
    const bS = h('button', {class: 'second', 'data-response': 'second', disabled: true}, 'Second',
      h('kbd', {text: keys.second.toUpperCase()}));
    const bR = s.replay ? h('button', {class: 'replay', text: 'Replay both', disabled: true}) : null;
    show(h('div', {class: 'progress'}, h('span', {text: `Trial ${s.trial} of ${s.of}`}),
      h('span', {text: `${keys.first.toUpperCase()} = first · ${keys.second.toUpperCase()} = second`})),
    h('div', {class: 'stage pair'}, ...videos, fix, label),
    h('p', {class: 'prompt', text: s.prompt}),
    h('div', {class: 'actions'}, bF, bS, bR));
    app.dataset.trial = String(s.trial);
    app.dataset.stimulus = s.stimulus;

    const [srcs] = await Promise.all([Promise.all(s.videos.map((u) => loadVideo(u))), sleep(s.iti_ms || 0)]);
    await Promise.all(videos.map((v, i) => prepare(v, srcs[i])));
    fix.classList.add('hidden');
    const labels = s.labels || ['1', '2'];
    const playPair = async () => {
      const out = [];
      app.dataset.playing = '1';
      for (let i = 0; i < 2; i++) {
        label.textContent = labels[i];
        label.classList.remove('hidden');
        app.dataset.interval = String(i + 1);
        if (i === 1) await sleep(s.gap_ms || 0);     // the blank gap, "2" already on the stage
        videos[i].classList.remove('hidden');
        out.push(await playMeasured(videos[i]));
        videos[i].classList.add('hidden');
      }
      label.classList.add('hidden');
      app.dataset.interval = '';
      app.dataset.playing = '0';
      return out;
    };
    const shown = await playPair();
    prefetch(ctx);

    const answer = await awaitAnswer([['first', bF, keys.first], ['second', bS, keys.second]], bR, playPair);
    ctx.next = (await postJSON(s.submit, {
      participant: ctx.data.participant, session: ctx.data.session, trial: s.trial,
      stimulus: s.stimulus, response: answer.response, rt_ms: round1(answer.rt_ms),
      shown_ms: round1(shown[0].shown_ms + shown[1].shown_ms),
      late_frames: shown[0].late_frames + shown[1].late_frames, replays: answer.replays, input: answer.input,
    })).next_trial;
    await Promise.all(s.videos.map((u) => dropVideo(u)));
  };

  // ---- runner --------------------------------------------------------------------------
  function fatal(e) {
    const btn = h('button', {class: 'primary', text: 'Reload'});
    btn.addEventListener('click', () => location.reload());
    app.dataset.screen = 'error';
    show(h('div', {class: 'card'}, h('h1', {text: 'Please call the experimenter'}),
      h('p', {text: 'The study cannot continue on this page. Your saved answers are safe.'}),
      h('p', {class: 'error', text: String(e && e.message || e)}),
      h('div', {class: 'actions'}, btn)));
  }

  async function main() {
    const data = await getJSON('/api/session');
    KEYS = data.keys;
    const ctx = {data, index: 0, next: null};
    for (let i = data.start; i < data.timeline.length; i++) {
      let s = data.timeline[i];
      // the server's next open trial: quest+ slots of a group that stopped early
      // (stop_width) are passed over, and so are breaks once nothing is left
      const isTrial = s.type === 'trial' || s.type === 'trial-2afc';
      if (ctx.next && ((isTrial && s.trial < ctx.next) || (s.type === 'break' && ctx.next > data.n_trials))) continue;
      // an adaptive trial: its level is chosen when it is served
      if (s.adaptive && !s.stimulus) s = await getJSON(`/api/trial/${s.trial}`);
      const plugin = plugins[s.type];
      if (!plugin) throw new Error(`unknown screen type ${s.type}`);
      ctx.index = i;
      app.dataset.screen = s.type;
      app.dataset.screenId = s.id;
      await plugin(s, ctx);
    }
  }
  main().catch(fatal);
})();
