/* pyrocam-launch: runs a gst-launch-1.0 pipeline description and always ends.
 *
 *   pyrocam-launch [-e] [-m] [--stop-timeout=SECONDS] [--stats-csv=FILE] [--alarm-csv=FILE]
 *                  ELEMENT [! ELEMENT ...]
 *
 * The words are parsed as gst-launch-1.0 parses them (gst_parse_launchv). Exit status: 0 at
 * end of stream, 1 after an error (the error, its element and its debug text on stderr), 2 for
 * a description that does not parse, a property value out of its range (which gst-launch-1.0
 * only warns about, keeping the default) or bad arguments. SIGINT and SIGTERM stop the pipeline
 * (status 0); with -e they send EOS instead, so that muxers finalise their files (as
 * gst-launch-1.0 -e), and the program exits when the EOS has gone through (status 0) or an
 * error comes; a second signal stops at once (status 130).
 *
 * gst-launch-1.0 of GStreamer 1.22 can hang after an early error (a race between its bus
 * handling and the state change that fails). This launcher never waits on the pipeline without
 * a bound: after an error, an EOS or a signal, stopping the pipeline (state NULL) gets
 * --stop-timeout seconds (default 10); past that it reports the stall and exits anyway, with
 * the status the pipeline had earned (1 if neither an error nor the end of stream came: the
 * files may not be finalised). -m prints element messages (e.g. ratiotemp's statistics)
 * on stdout, as gst-launch-1.0 -m does. Scripts in pipelines/ run their pipelines with it.
 *
 * --stats-csv=FILE writes every "pyrocam-temperature-stats" message (ratiotemp's statistics) as
 * a CSV row, --alarm-csv=FILE every "pyrocam-alarm" message (thermalalarm's changes of state):
 * a header line, then one row per message, flushed at once so that Ctrl-C or a crash loses no
 * row. The columns are fixed (see stats_columns and alarm_columns below: "element", the
 * element's name, then the message's documented fields in order); a field a message lacks
 * (e.g. min-c in a frame without readings, the region fields without a region) is an empty
 * cell, as is an unknown time (GST_CLOCK_TIME_NONE). A file that cannot be created is exit 2.
 */
#include <errno.h>
#include <glib-unix.h>
#include <glib.h>
#include <gst/gst.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

/* A CSV file of one kind of element message. */
typedef struct {
  const char* message;        /* structure name of the messages it takes */
  const char* const* columns; /* NULL-terminated; "element" is the posting element's name */
  FILE* file;
} CsvLog;

/* Columns added later go last, so that readers of older files keep their indices; a table is
 * easier to read than one name per line. */
/* clang-format off */
static const char* const stats_columns[] = {
    "element",       "timestamp",      "stream-time",   "running-time",
    "method",        "width",          "height",        "pixels",
    "valid",         "valid-fraction", "min-c",         "max-c",
    "mean-c",        "median-c",       "peak-c",        "peak-x",
    "peak-y",        "region-x",       "region-y",      "region-width",
    "region-height", "region-pixels",  "region-valid",  "region-valid-fraction",
    "region-min-c",  "region-max-c",   "region-mean-c", "region-median-c",
    "region-peak-c", "region-peak-x",  "region-peak-y", "saturated",
    "region-saturated", "region-tracks-peak", "above-range", "region-above-range",
    "peak-u-sys-c",  "region-peak-u-sys-c", NULL};
/* clang-format on */
static const char* const alarm_columns[] = {
    "element",      "state",         "active",    "statistic",    "value-c",  "threshold-c",
    "clear-c",      "frames",        "timestamp", "running-time", "region-x", "region-y",
    "region-width", "region-height", "saturated", "above-range",  NULL};

typedef struct {
  GMainLoop* loop;
  GstElement* pipeline;
  gint status;            /* exit status earned so far (atomic: the guard thread reads it) */
  guint signals;          /* signals received */
  guint stop_timeout_s;   /* bound on stopping the pipeline */
  gboolean messages;      /* -m */
  gboolean eos_on_signal; /* -e */
  gboolean finalising;    /* -e: an EOS sent after an error, awaited */
  CsvLog stats_csv;       /* --stats-csv */
  CsvLog alarm_csv;       /* --alarm-csv */
} Launch;

static Launch launch_state;
static gint stop_guard_armed = 0;
static gint eos_seen = 0; /* the end of stream went through: the files are finalised */

/* Runs in its own thread: if the pipeline has not stopped in time, exit without it. */
static gpointer stop_guard(gpointer data) {
  const guint seconds = GPOINTER_TO_UINT(data);
  g_usleep((gulong)seconds * G_USEC_PER_SEC);
  fprintf(stderr,
          "pyrocam-launch: the pipeline did not stop within %u s; exiting without waiting "
          "for it\n",
          seconds);
  fflush(stderr);
  /* Without an error and without the end of stream, the files may not be finalised. */
  const int status = g_atomic_int_get(&launch_state.status);
  _exit(status == 0 && !g_atomic_int_get(&eos_seen) ? 1 : status);
  return NULL;
}

static void arm_stop_guard(const Launch* launch) {
  if (g_atomic_int_compare_and_exchange(&stop_guard_armed, 0, 1)) {
    GThread* t = g_thread_new("stop-guard", stop_guard, GUINT_TO_POINTER(launch->stop_timeout_s));
    g_thread_unref(t);
  }
}

static void print_error(GstMessage* msg) {
  GError* err = NULL;
  gchar* debug = NULL;
  gst_message_parse_error(msg, &err, &debug);
  gchar* path = gst_object_get_path_string(GST_MESSAGE_SRC(msg));
  fprintf(stderr, "ERROR: from element %s: %s\n", path, err ? err->message : "(no message)");
  if (debug) fprintf(stderr, "Additional debug info:\n%s\n", debug);
  fflush(stderr);
  g_free(path);
  g_free(debug);
  g_clear_error(&err);
}

static void print_warning(GstMessage* msg) {
  GError* err = NULL;
  gchar* debug = NULL;
  gst_message_parse_warning(msg, &err, &debug);
  gchar* path = gst_object_get_path_string(GST_MESSAGE_SRC(msg));
  fprintf(stderr, "WARNING: from element %s: %s\n", path, err ? err->message : "(no message)");
  if (debug) fprintf(stderr, "Additional debug info:\n%s\n", debug);
  fflush(stderr);
  g_free(path);
  g_free(debug);
  g_clear_error(&err);
}

/* A cell: text with a comma, quote or line break is quoted, quotes doubled. */
static void write_cell(FILE* f, const gchar* text) {
  if (!strpbrk(text, ",\"\r\n")) {
    fputs(text, f);
    return;
  }
  fputc('"', f);
  for (const gchar* c = text; *c; ++c) {
    if (*c == '"') fputc('"', f);
    fputc(*c, f);
  }
  fputc('"', f);
}

/* A field's value as a cell: numbers in the C locale (doubles to their shortest exact form),
 * times of GST_CLOCK_TIME_NONE empty. */
static gchar* cell_text(const GValue* v) {
  if (G_VALUE_HOLDS_DOUBLE(v)) {
    gchar buf[G_ASCII_DTOSTR_BUF_SIZE];
    return g_strdup(g_ascii_dtostr(buf, sizeof buf, g_value_get_double(v)));
  }
  if (G_VALUE_HOLDS_UINT64(v)) {
    const guint64 u = g_value_get_uint64(v);
    return u == GST_CLOCK_TIME_NONE ? g_strdup("") : g_strdup_printf("%" G_GUINT64_FORMAT, u);
  }
  if (G_VALUE_HOLDS_BOOLEAN(v)) return g_strdup(g_value_get_boolean(v) ? "true" : "false");
  if (G_VALUE_HOLDS_STRING(v)) return g_value_dup_string(v);
  return gst_value_serialize(v);
}

static void write_header(const CsvLog* log) {
  for (const char* const* c = log->columns; *c; ++c) {
    if (c != log->columns) fputc(',', log->file);
    fputs(*c, log->file);
  }
  fputc('\n', log->file);
  fflush(log->file);
}

static void write_row(const CsvLog* log, GstMessage* msg, const GstStructure* s) {
  for (const char* const* c = log->columns; *c; ++c) {
    if (c != log->columns) fputc(',', log->file);
    if (g_str_equal(*c, "element")) {
      write_cell(log->file, GST_OBJECT_NAME(GST_MESSAGE_SRC(msg)));
      continue;
    }
    const GValue* v = gst_structure_get_value(s, *c);
    if (!v) continue;
    gchar* text = cell_text(v);
    if (text) write_cell(log->file, text);
    g_free(text);
  }
  fputc('\n', log->file);
  fflush(log->file); /* Ctrl-C, a kill or a crash loses no row */
}

/* Opens a CSV log for --stats-csv / --alarm-csv and writes its header; FALSE with a message. */
static gboolean open_csv(CsvLog* log, const char* option, const char* path) {
  if (log->file) fclose(log->file);
  log->file = *path ? fopen(path, "w") : NULL;
  if (!log->file) {
    fprintf(stderr, "pyrocam-launch: %s: cannot create '%s': %s\n", option, path,
            *path ? g_strerror(errno) : "empty file name");
    return FALSE;
  }
  write_header(log);
  return TRUE;
}

/* An end of stream into what each source feeds, past the source itself: after an error the
 * source's own thread may be stuck on, or failing with, a camera that is gone, and an EOS event
 * sent to the pipeline goes to that thread (aravissrc then stops with an error instead). */
static void end_streams_after_sources(GstElement* pipeline) {
  GstIterator* sources = gst_bin_iterate_sources(GST_BIN(pipeline));
  GValue item = G_VALUE_INIT;
  while (gst_iterator_next(sources, &item) == GST_ITERATOR_OK) {
    GstElement* source = g_value_get_object(&item);
    GstIterator* pads = gst_element_iterate_src_pads(source);
    GValue pad_item = G_VALUE_INIT;
    while (gst_iterator_next(pads, &pad_item) == GST_ITERATOR_OK) {
      GstPad* peer = gst_pad_get_peer(g_value_get_object(&pad_item));
      if (peer) {
        gst_pad_send_event(peer, gst_event_new_eos());
        gst_object_unref(peer);
      }
      g_value_reset(&pad_item);
    }
    g_value_unset(&pad_item);
    gst_iterator_free(pads);
    g_value_reset(&item);
  }
  g_value_unset(&item);
  gst_iterator_free(sources);
}

/* How long an end of stream sent after an error may take to come through (-e). */
enum { kFinaliseAfterErrorMs = 3000 };

static gboolean quit_loop(gpointer loop) {
  g_main_loop_quit(loop);
  return G_SOURCE_REMOVE;
}

static gboolean on_bus(GstBus* bus, GstMessage* msg, gpointer data) {
  (void)bus;
  Launch* launch = data;
  switch (GST_MESSAGE_TYPE(msg)) {
    case GST_MESSAGE_ERROR:
      print_error(msg);
      g_atomic_int_set(&launch->status, 1);
      if (launch->finalising) break; /* the source's own error after the first: still waiting */
      if (launch->eos_on_signal && !g_atomic_int_get(&eos_seen) &&
          GST_STATE(launch->pipeline) == GST_STATE_PLAYING) { /* else no file was begun */
        /* With -e the files are finalised after an error too, as far as the pipeline lets an
         * end of stream through (a camera that vanished mid-segment: the segment being
         * written keeps its frames and its index); bounded by the stop guard. */
        launch->finalising = TRUE;
        fprintf(stderr, "pyrocam-launch: error: sending EOS so that the files are finalised\n");
        fflush(stderr);
        end_streams_after_sources(launch->pipeline);
        /* A pipeline whose stream stopped at the error passes no end of stream: not long. */
        g_timeout_add(kFinaliseAfterErrorMs, quit_loop, launch->loop);
        break;
      }
      g_main_loop_quit(launch->loop);
      break;
    case GST_MESSAGE_WARNING:
      print_warning(msg);
      break;
    case GST_MESSAGE_EOS:
      fprintf(stderr, "Got EOS from element %s.\n", GST_OBJECT_NAME(GST_MESSAGE_SRC(msg)));
      g_atomic_int_set(&eos_seen, 1);
      g_main_loop_quit(launch->loop);
      break;
    case GST_MESSAGE_ELEMENT: {
      /* Element messages (e.g. ratiotemp's statistics) on stdout, as gst-launch-1.0 -m. */
      const GstStructure* s = gst_message_get_structure(msg);
      if (s && launch->stats_csv.file && gst_structure_has_name(s, launch->stats_csv.message))
        write_row(&launch->stats_csv, msg, s);
      if (s && launch->alarm_csv.file && gst_structure_has_name(s, launch->alarm_csv.message))
        write_row(&launch->alarm_csv, msg, s);
      if (s && launch->messages) {
        gchar* text = gst_structure_to_string(s);
        printf("%s\n", text);
        fflush(stdout);
        g_free(text);
      }
      break;
    }
    default:
      break;
  }
  return G_SOURCE_CONTINUE;
}

static gboolean on_signal(gpointer data) {
  Launch* launch = data;
  ++launch->signals;
  if (launch->signals == 1 && !launch->eos_on_signal) {
    fprintf(stderr, "pyrocam-launch: interrupt: stopping the pipeline\n");
    fflush(stderr);
    g_main_loop_quit(launch->loop);
  } else if (launch->signals == 1) {
    fprintf(stderr, "pyrocam-launch: interrupt: sending EOS so that the files are finalised\n");
    fflush(stderr);
    gst_element_send_event(launch->pipeline, gst_event_new_eos());
    arm_stop_guard(launch); /* the EOS must get through in bounded time too */
  } else {
    fprintf(stderr, "pyrocam-launch: second interrupt: stopping without finalising\n");
    fflush(stderr);
    _exit(130);
  }
  return G_SOURCE_CONTINUE;
}

static void print_usage(FILE* to) {
  fprintf(to,
          "usage: pyrocam-launch [-e] [-m] [--stop-timeout=SECONDS] [--stats-csv=FILE]\n"
          "                      [--alarm-csv=FILE] ELEMENT [! ELEMENT ...]\n"
          "Runs a gst-launch-1.0 pipeline: exit 0 at end of stream, 1 after an error, 2 for\n"
          "a description, property value or option it cannot take. -e: SIGINT and SIGTERM\n"
          "send end of stream (files are finalised); -m: print element messages; --stats-csv,\n"
          "--alarm-csv: ratiotemp's statistics and thermalalarm's messages as CSV rows;\n"
          "--stop-timeout: how long to wait for the pipeline to stop (default 10 s).\n");
}

/* Keeps the first GObject warning of the parse (a property value refused) in `data`. */
static void note_refused_value(const gchar* domain, GLogLevelFlags level, const gchar* message,
                               gpointer data) {
  (void)domain;
  (void)level;
  GString* refused = data;
  if (refused->len == 0) g_string_append(refused, message);
}

int main(int argc, char** argv) {
  Launch* launch = &launch_state;
  launch->stop_timeout_s = 10;
  launch->stats_csv = (CsvLog){"pyrocam-temperature-stats", stats_columns, NULL};
  launch->alarm_csv = (CsvLog){"pyrocam-alarm", alarm_columns, NULL};
  int first = 1;
  for (; first < argc; ++first) {
    if (g_str_equal(argv[first], "-m")) {
      launch->messages = TRUE;
    } else if (g_str_equal(argv[first], "-e")) {
      launch->eos_on_signal = TRUE;
    } else if (g_str_has_prefix(argv[first], "--stop-timeout=")) {
      gchar* end = NULL;
      const gint64 v = g_ascii_strtoll(argv[first] + strlen("--stop-timeout="), &end, 10);
      if (!end || *end || v < 1 || v > 3600) {
        fprintf(stderr, "pyrocam-launch: --stop-timeout must be 1..3600 seconds, not '%s'\n",
                argv[first] + strlen("--stop-timeout="));
        return 2;
      }
      launch->stop_timeout_s = (guint)v;
    } else if (g_str_has_prefix(argv[first], "--stats-csv=")) {
      if (!open_csv(&launch->stats_csv, "--stats-csv", argv[first] + strlen("--stats-csv=")))
        return 2;
    } else if (g_str_has_prefix(argv[first], "--alarm-csv=")) {
      if (!open_csv(&launch->alarm_csv, "--alarm-csv", argv[first] + strlen("--alarm-csv=")))
        return 2;
    } else if (g_str_equal(argv[first], "-h") || g_str_equal(argv[first], "--help")) {
      print_usage(stdout);
      return 0;
    } else if (g_str_has_prefix(argv[first], "-")) {
      /* A pipeline description never starts with '-': an option misspelt, or its value
       * given after a space. */
      fprintf(stderr,
              "pyrocam-launch: unknown option '%s' (values follow an '=', as in "
              "--stats-csv=FILE)\n",
              argv[first]);
      print_usage(stderr);
      return 2;
    } else {
      break;
    }
  }
  gst_init(NULL, NULL);
  if (argc <= first) {
    print_usage(stderr);
    return 2;
  }

  GError* error = NULL;
  /* A property value out of its range is only a GObject warning, and the element keeps its
   * default: a setting silently not taken (threshold-c=nan leaves an alarm off). Refused here. */
  GString* refused = g_string_new(NULL);
  const guint handler = g_log_set_handler(
      "GLib-GObject", G_LOG_LEVEL_WARNING | G_LOG_LEVEL_CRITICAL, note_refused_value, refused);
  GstElement* pipeline = gst_parse_launchv_full((const gchar**)&argv[first], NULL,
                                                GST_PARSE_FLAG_FATAL_ERRORS, &error);
  g_log_remove_handler("GLib-GObject", handler);
  if (!pipeline || error || refused->len > 0) {
    fprintf(stderr, "pyrocam-launch: could not build the pipeline: %s\n",
            error              ? error->message
            : refused->len > 0 ? refused->str
                               : "unknown error");
    g_clear_error(&error);
    g_string_free(refused, TRUE);
    if (pipeline) gst_object_unref(pipeline);
    return 2;
  }
  g_string_free(refused, TRUE);
  if (!GST_IS_PIPELINE(pipeline)) {
    GstElement* wrapped = gst_pipeline_new(NULL);
    gst_bin_add(GST_BIN(wrapped), pipeline);
    pipeline = wrapped;
  }

  launch->loop = g_main_loop_new(NULL, FALSE);
  launch->pipeline = pipeline;
  GstBus* bus = gst_element_get_bus(pipeline);
  gst_bus_add_watch(bus, on_bus, launch);
  const guint sigint = g_unix_signal_add(SIGINT, on_signal, launch);
  const guint sigterm = g_unix_signal_add(SIGTERM, on_signal, launch);

  if (gst_element_set_state(pipeline, GST_STATE_PLAYING) == GST_STATE_CHANGE_FAILURE) {
    /* The reason is an error message on the bus; report it (or say there was none). */
    GstMessage* msg = gst_bus_pop_filtered(bus, GST_MESSAGE_ERROR);
    if (msg) {
      print_error(msg);
      gst_message_unref(msg);
    } else {
      fprintf(stderr, "pyrocam-launch: the pipeline refused to start\n");
    }
    g_atomic_int_set(&launch->status, 1);
  } else {
    g_main_loop_run(launch->loop);
  }

  /* Stopping may block on a stuck streaming thread: bounded by the guard thread. */
  arm_stop_guard(launch);
  g_source_remove(sigint);
  g_source_remove(sigterm);
  gst_element_set_state(pipeline, GST_STATE_NULL);
  gst_bus_remove_watch(bus);
  gst_object_unref(bus);
  gst_object_unref(pipeline);
  g_main_loop_unref(launch->loop);
  if (launch->stats_csv.file) fclose(launch->stats_csv.file);
  if (launch->alarm_csv.file) fclose(launch->alarm_csv.file);
  return g_atomic_int_get(&launch->status);
}
