/* thermalalarm: a temperature alarm on a region of the temperature stream (GRAY16_LE, 0.1 K). */
#pragma once

#include <gst/gst.h>
#include <gst/video/gstvideofilter.h>

G_BEGIN_DECLS

#define GST_TYPE_THERMAL_ALARM (gst_thermal_alarm_get_type())
G_DECLARE_FINAL_TYPE(GstThermalAlarm, gst_thermal_alarm, GST, THERMAL_ALARM, GstVideoFilter)

typedef enum {
  GST_THERMAL_ALARM_STATISTIC_MEDIAN,
  GST_THERMAL_ALARM_STATISTIC_PEAK,
} GstThermalAlarmStatistic;
#define GST_TYPE_THERMAL_ALARM_STATISTIC (gst_thermal_alarm_statistic_get_type())
GType gst_thermal_alarm_statistic_get_type(void);

GST_ELEMENT_REGISTER_DECLARE(thermalalarm);

G_END_DECLS
