// flipstudy web: the two-alternative forced-choice trial on jsPsych's plugins (the local
// page's trial-2afc screen).  The two motions play one after the other, each a
// video-button-response trial without buttons that ends with its video, a label "1" / "2"
// over the stage, a blank gap (html-keyboard-response, no keys) between them; then an
// html-button-response asks "Which motion was physically correct?" (First / Second, keys
// F / J; with replay allowed, "Replay both" runs the pair again: a loop node).
//
// `t.pair` is the trial's two videos (their opaque names) in the order shown; the page is
// not told which is the original.  The answer record is the yes/no one with task = "2afc",
// the pair as shown and response "first" | "second" (the interval chosen); the server
// (local) or import-web (the site's map) works out which was the original.  Its playback fields add up both motions' first showings (frames expected,
// presented and dropped, playback_ms, video_ms, shown_ms), so a dropped frame in either is
// counted and flagged against max_dropped_pct as for one motion.
'use strict';
(function (root) {
  // env: {C, jsPsych, esc, setScreen, watchPlayback, answerKeys, arrange, loadNode, record, refresh, n, app};
  // record(rec) may return a Promise (the local runner: the trial ends once the server stored it).
  // `t` may be filled only when the trial starts (a QUEST+ trial of the local runner), so
  // its stimuli are read late.
  function nodes(t, repeat, env) {
    const {C, jsPsych, esc, setScreen, watchPlayback, answerKeys, arrange, record} = env;
    const keys = C.keys_2afc;
    const sid = repeat ? `repeat-${t.trial}` : `trial-${t.trial}`;
    const progress = repeat ? `Once more: trial ${t.trial} of ${env.n}` : `Trial ${t.trial} of ${env.n}`;
    const infos = () => t.pair.map((s) => C.videos[s]);
    const head = `<p class="fs-progress"><span>${esc(progress)}</span><span>${esc(keys.first.toUpperCase())} = first · ${esc(keys.second.toUpperCase())} = second</span></p>`;
    const question = `<p class="fs-prompt">${esc(C.texts.prompt_2afc)}</p>`;
    const fix = `<div class="fs-stage"><div class="fs-fixation">+</div></div>`;
    const label = (i) => `<div class="fs-stage"><div class="fs-interval">${esc(String(i))}</div></div>`;
    let input = 'click', tEnabled = null, onKey = null, replays = 0, first = null;
    let watches = [];

    const motion = (i) => ({
      type: jsPsychVideoButtonResponse, stimulus: () => [infos()[i].video], choices: [],
      prompt: head + question, trial_ends_after_video: true, response_allowed_while_playing: false,
      autoplay: true, controls: false, width: C.video_width,
      on_load: () => {
        setScreen(sid, 'trial-2afc');
        const el = env.app();
        el.dataset.trial = String(t.trial);
        el.dataset.stimulus = t.pair[i];
        el.dataset.playing = '1';
        el.dataset.interval = String(i + 1);
        const v = document.getElementById('jspsych-video-button-response-stimulus');
        v.muted = true;
        v.setAttribute('playsinline', '');
        v.disablePictureInPicture = true;
        const wrap = v.parentElement;
        wrap.classList.add('fs-pair');
        wrap.insertAdjacentHTML('beforeend', `<div class="fs-interval">${i + 1}</div>`);
        watches[i] = watchPlayback(v, infos()[i]);
        arrange(v, document.getElementById('jspsych-video-button-response-btngroup'));
      },
      on_finish: () => { watches[i] = watches[i].result(); },
    });

    const gap = {type: jsPsychHtmlKeyboardResponse, stimulus: head + label(2) + question, choices: 'NO_KEYS',
                 trial_duration: C.gap_ms, on_load: () => { env.app().dataset.interval = '2'; }};

    const choose = {
      type: jsPsychHtmlButtonResponse, stimulus: head + fix.replace('+', '') + question,
      choices: ['First', 'Second'].concat(C.replay ? ['Replay both'] : []),
      button_html: (c) => {
        const cls = c === 'First' ? 'first' : c === 'Second' ? 'second' : 'replay';
        const k = keys[cls];
        return `<button class="jspsych-btn fs-${cls}">${esc(c)}${k ? ` <kbd>${esc(k.toUpperCase())}</kbd>` : ''}</button>`;
      },
      on_load: () => {
        const el = env.app();
        el.dataset.playing = '0';
        el.dataset.interval = '';
        if (tEnabled === null) tEnabled = performance.now();
        if (first === null) first = watches.slice();      // the first showing's playback
        const buttons = document.querySelectorAll('#jspsych-html-button-response-btngroup button');
        onKey = answerKeys(buttons, keys.first, keys.second, () => { input = 'key'; });
        document.addEventListener('keydown', onKey);
      },
      on_finish: (data) => {
        document.removeEventListener('keydown', onKey);
        if (data.response === 2) { replays += 1; input = 'click'; watches = []; return; }
        const tAnswer = performance.now();
        const vb = jsPsych.pluginAPI.video_buffers;
        for (const info of infos()) if (vb && vb[info.video]) { URL.revokeObjectURL(vb[info.video]); delete vb[info.video]; }
        // the site's records still say what its order gave (stimulus, first, original)
        const shown = t.first ? {stimulus: t.stimulus, first: t.first, original: t.original} : {pair: t.pair.join(' ')};
        return record(Object.assign({record: 'answer', trial: t.trial}, shown, {group: t.group,
          repetition: t.repetition, task: '2afc',
          response: data.response === 0 ? 'first' : 'second',
          rt_ms: Math.round((tAnswer - (tEnabled === null ? tAnswer : tEnabled)) * 10) / 10, input, replays, repeat,
          refresh_hz: env.refresh, max_dropped_pct: C.max_dropped_pct}, combine(first, C.max_dropped_pct)));
      },
    };

    return [
      env.loadNode(() => infos().map((x) => x.video), fix, `load-${sid}`),
      {type: jsPsychHtmlKeyboardResponse, stimulus: fix, choices: 'NO_KEYS', trial_duration: C.iti_ms,
       on_load: () => setScreen(`iti-${sid}`, 'iti')},
      {timeline: [motion(0), gap, motion(1), choose],
       loop_function: (data) => data.values().slice(-1)[0].response === 2},
    ];
  }

  // the two motions' playback records as one
  function combine(pb, maxPct) {
    const sum = (k) => pb[0][k] + pb[1][k];
    const expected = sum('frames_expected');
    const dropped = sum('frames_dropped');
    const pct = expected > 0 ? 100 * dropped / expected : 0;
    const r1 = (x) => Math.round(x * 10) / 10;
    return {shown_ms: r1(sum('shown_ms')), frames_expected: expected, frames_presented: sum('frames_presented'),
            frames_dropped: dropped, frames_seen: sum('frames_seen'), dropped_pct: r1(pct),
            playback_ms: r1(sum('playback_ms')), video_ms: r1(sum('video_ms')), timing: pb[0].timing,
            playback_flagged: pct > maxPct};
  }

  root.Flipstudy2afc = {nodes, combine};
})(typeof window !== 'undefined' ? window : globalThis);
