/* pyrocam-launch: runs a gst-launch-1.0 pipeline description and always ends.
 *
 *   pyrocam-launch [-e] [-m] [--stop-timeout=SECONDS] ELEMENT [! ELEMENT ...]
 *
 * The words are parsed as gst-launch-1.0 parses them (gst_parse_launchv). Exit status: 0 at
 * end of stream, 1 after an error (the error, its element and its debug text on stderr), 2 for
 * a description that does not parse or bad arguments. SIGINT and SIGTERM stop the pipeline
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
 */
#include <glib-unix.h>
#include <glib.h>
#include <gst/gst.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

typedef struct {
  GMainLoop* loop;
  GstElement* pipeline;
  gint status;            /* exit status earned so far (atomic: the guard thread reads it) */
  guint signals;          /* signals received */
  guint stop_timeout_s;   /* bound on stopping the pipeline */
  gboolean messages;      /* -m */
  gboolean eos_on_signal; /* -e */
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

static gboolean on_bus(GstBus* bus, GstMessage* msg, gpointer data) {
  (void)bus;
  Launch* launch = data;
  switch (GST_MESSAGE_TYPE(msg)) {
    case GST_MESSAGE_ERROR:
      print_error(msg);
      g_atomic_int_set(&launch->status, 1);
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

int main(int argc, char** argv) {
  Launch* launch = &launch_state;
  launch->stop_timeout_s = 10;
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
    } else {
      break;
    }
  }
  gst_init(NULL, NULL);
  if (argc <= first) {
    fprintf(stderr,
            "usage: pyrocam-launch [-e] [-m] [--stop-timeout=SECONDS] ELEMENT [! ELEMENT ...]\n"
            "Runs a gst-launch-1.0 pipeline: exit 0 at end of stream, 1 after an error.\n");
    return 2;
  }

  GError* error = NULL;
  GstElement* pipeline = gst_parse_launchv_full((const gchar**)&argv[first], NULL,
                                                GST_PARSE_FLAG_FATAL_ERRORS, &error);
  if (!pipeline || error) {
    fprintf(stderr, "pyrocam-launch: could not build the pipeline: %s\n",
            error ? error->message : "unknown error");
    g_clear_error(&error);
    if (pipeline) gst_object_unref(pipeline);
    return 2;
  }
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
  return g_atomic_int_get(&launch->status);
}
