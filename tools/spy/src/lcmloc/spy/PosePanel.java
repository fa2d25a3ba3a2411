package lcmloc.spy;

import java.awt.BasicStroke;
import java.awt.Color;
import java.awt.Dimension;
import java.awt.Graphics;
import java.awt.Graphics2D;
import java.awt.RenderingHints;
import java.awt.geom.Path2D;
import java.util.HashMap;
import java.util.List;
import java.util.Map;

import javax.swing.JPanel;

/**
 * Paints a {@link PoseModel}: above, the map, the gate's decisions, the track, the scaled 3-sigma
 * ellipse and the vehicle in world coordinates (x right, y up, equal scale); below, the NIS strip
 * against its 95 % chi-square band. Holds no state but what it paints from.
 */
public final class PosePanel extends JPanel {
    static final Color TRACK = new Color(30, 90, 200);
    static final Color ELLIPSE = new Color(230, 120, 0);
    static final Color ACCEPTED = new Color(0, 160, 60);
    static final Color REJECTED = new Color(220, 30, 30);
    static final Color MAP = new Color(110, 110, 110);
    static final Color BAND = new Color(200, 225, 200);
    private static final int STRIP = 130;
    private static final int SHOWN_MARKS = 60;

    private final PoseModel model;
    private final String title;
    private final List<MapCsv.Element> map;
    private final Map<Integer, MapCsv.Element> byId = new HashMap<>();
    private final String mapNote;

    public PosePanel(PoseModel model, String title, List<MapCsv.Element> map, String mapNote) {
        this.model = model;
        this.title = title;
        this.map = map;
        this.mapNote = mapNote;
        for (MapCsv.Element e : map) {
            byId.put(e.id, e);
        }
        setBackground(Color.WHITE);
        setPreferredSize(new Dimension(720, 620));
    }

    @Override
    protected void paintComponent(Graphics graphics) {
        super.paintComponent(graphics);
        Graphics2D g = (Graphics2D) graphics;
        g.setRenderingHint(RenderingHints.KEY_ANTIALIASING, RenderingHints.VALUE_ANTIALIAS_ON);
        PoseModel.Snapshot s = model.snapshot();
        int w = getWidth();
        int h = getHeight() - STRIP;
        paintWorld(g, s, w, h);
        paintStrip(g, s, 0, h, w, STRIP);
    }

    private void paintWorld(Graphics2D g, PoseModel.Snapshot s, int w, int h) {
        View v = View.fit(s, map, w, h - 40, 40);
        g.setColor(Color.BLACK);
        g.drawString(title + "  filter " + s.filter + "  status " + statusName(s.status) + "  poses " + s.poses
            + "  decisions " + s.decisions, 6, 14);
        g.drawString(mapNote, 6, 30);
        if (v == null) {
            g.drawString("waiting for pose_t messages", 6, 50);
            return;
        }
        g.setColor(MAP);
        for (MapCsv.Element e : map) {
            g.fillRect(v.px(e.x) - 2, v.py(e.y) - 2, 5, 5);
        }
        int from = Math.max(0, s.marks.size() - SHOWN_MARKS);
        for (int pass = 0; pass < 2; ++pass) { // rejected last, so that accepted ones do not hide them
            for (PoseModel.Mark m : s.marks.subList(from, s.marks.size())) {
                if (m.accepted != (pass == 0)) {
                    continue;
                }
                paintMark(g, v, m);
            }
        }
        g.setColor(TRACK);
        g.setStroke(new BasicStroke(1.5f));
        Path2D.Double track = new Path2D.Double();
        for (int i = 0; i < s.track.size(); ++i) {
            PoseModel.Point p = s.track.get(i);
            if (i == 0) {
                track.moveTo(v.fx(p.x), v.fy(p.y));
            } else {
                track.lineTo(v.fx(p.x), v.fy(p.y));
            }
        }
        g.draw(track);
        PoseModel.Point last = s.last();
        if (s.covariance != null) {
            Ellipse e = Ellipse.of(s.covariance[0], s.covariance[1], s.covariance[2], 3.0);
            double k = Ellipse.visibleScale(e.major, v.extent, 0.03);
            double[] xy = e.scaled(k).points(last.x, last.y, 72);
            Path2D.Double outline = new Path2D.Double();
            outline.moveTo(v.fx(xy[0]), v.fy(xy[1]));
            for (int i = 1; i < xy.length / 2; ++i) {
                outline.lineTo(v.fx(xy[2 * i]), v.fy(xy[2 * i + 1]));
            }
            outline.closePath();
            g.setColor(ELLIPSE);
            g.setStroke(new BasicStroke(2.5f));
            g.draw(outline);
            g.drawString(String.format("3\u03c3 ellipse x%s: semi-axes %.3g m, %.3g m (drawn %s times larger)",
                fmt(k), e.major, e.minor, fmt(k)), 6, h - 4);
        }
        g.setStroke(new BasicStroke(1.0f));
        g.setColor(Color.BLACK);
        int cx = v.px(last.x);
        int cy = v.py(last.y);
        g.fillOval(cx - 4, cy - 4, 9, 9);
        g.drawLine(cx, cy, cx + (int) Math.round(16 * Math.cos(last.theta)),
            cy - (int) Math.round(16 * Math.sin(last.theta)));
    }

    private void paintMark(Graphics2D g, View v, PoseModel.Mark m) {
        g.setColor(m.accepted ? ACCEPTED : REJECTED);
        MapCsv.Element e = byId.get(m.markerId);
        if (e != null) {
            g.drawLine(v.px(m.x), v.py(m.y), v.px(e.x), v.py(e.y));
            g.drawOval(v.px(e.x) - 5, v.py(e.y) - 5, 10, 10);
        } else {
            g.drawOval(v.px(m.x) - 4, v.py(m.y) - 4, 8, 8);
        }
    }

    static String statusName(int status) {
        switch (status) {
            case 0: return "ok";
            case 1: return "dead reckoning";
            case 2: return "lock-out";
            case 3: return "uninitialized";
            default: return String.valueOf(status);
        }
    }

    private static String fmt(double k) {
        return k == Math.rint(k) ? String.valueOf((long) k) : String.valueOf(k);
    }

    private void paintStrip(Graphics2D g, PoseModel.Snapshot s, int x0, int y0, int w, int h) {
        g.setColor(new Color(245, 245, 245));
        g.fillRect(x0, y0, w, h);
        g.setColor(Color.BLACK);
        g.drawLine(x0, y0, x0 + w, y0);
        double top = 0.0;
        for (PoseModel.Nis n : s.nis) {
            top = Math.max(top, Double.isNaN(n.high) ? 0.0 : 1.5 * n.high);
        }
        top = Math.max(top, 1.0);
        int plotTop = y0 + 18;
        int plotH = h - 24;
        int count = s.nis.size();
        double dx = count > 0 ? (double) w / Math.max(count, 50) : 0.0;
        for (int i = 0; i < count; ++i) {
            PoseModel.Nis n = s.nis.get(i);
            int x = x0 + (int) Math.round(i * dx);
            if (!Double.isNaN(n.low)) {
                g.setColor(BAND);
                int yl = plotTop + plotH - (int) Math.round(plotH * n.low / top);
                int yh = plotTop + plotH - (int) Math.round(plotH * Math.min(n.high, top) / top);
                g.fillRect(x, yh, Math.max(1, (int) Math.ceil(dx)), yl - yh + 1);
            }
        }
        for (int i = 0; i < count; ++i) {
            PoseModel.Nis n = s.nis.get(i);
            int x = x0 + (int) Math.round(i * dx + dx / 2);
            int y = plotTop + plotH - (int) Math.round(plotH * Math.min(n.value, top) / top);
            g.setColor(!n.accepted ? REJECTED : n.inBand() ? ACCEPTED : ELLIPSE);
            g.fillOval(x - 2, y - 2, 5, 5);
        }
        g.setColor(Color.BLACK);
        double in = s.inBandFraction();
        g.drawString(String.format("NIS, last %d decisions; band: 95 %% \u03c7\u00b2 of their dim; %s inside; "
            + "red: rejected", count,
            Double.isNaN(in) ? "-" : String.format("%.0f %%", 100 * in)), x0 + 6, y0 + 14);
    }

    /** World-to-pixel transform fitted to the map, the track and the ellipse. */
    static final class View {
        final double minX;
        final double maxY;
        final double scale;
        final double extent;
        final int left;
        final int top;

        private View(double minX, double maxY, double scale, double extent, int left, int top) {
            this.minX = minX;
            this.maxY = maxY;
            this.scale = scale;
            this.extent = extent;
            this.left = left;
            this.top = top;
        }

        static View fit(PoseModel.Snapshot s, List<MapCsv.Element> map, int w, int h, int top) {
            if (s.track.isEmpty()) {
                return null;
            }
            double[] b = {Double.MAX_VALUE, Double.MAX_VALUE, -Double.MAX_VALUE, -Double.MAX_VALUE};
            for (PoseModel.Point p : s.track) {
                grow(b, p.x, p.y);
            }
            for (MapCsv.Element e : map) {
                grow(b, e.x, e.y);
            }
            double extent = Math.max(Math.max(b[2] - b[0], b[3] - b[1]), 1.0);
            double margin = 0.08 * extent;
            double sx = (w - 20) / (b[2] - b[0] + 2 * margin);
            double sy = (h - 20) / (b[3] - b[1] + 2 * margin);
            double scale = Math.max(Math.min(sx, sy), 1e-9);
            return new View(b[0] - margin, b[3] + margin, scale, extent, 10, top + 10);
        }

        private static void grow(double[] b, double x, double y) {
            b[0] = Math.min(b[0], x);
            b[1] = Math.min(b[1], y);
            b[2] = Math.max(b[2], x);
            b[3] = Math.max(b[3], y);
        }

        double fx(double x) { return left + (x - minX) * scale; }

        double fy(double y) { return top + (maxY - y) * scale; }

        int px(double x) { return (int) Math.round(fx(x)); }

        int py(double y) { return (int) Math.round(fy(y)); }
    }
}
