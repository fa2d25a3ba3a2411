package lcmloc.spy;

import java.io.DataInput;
import java.io.IOException;
import java.util.Collections;
import java.util.List;

import lcmloc.gate_decision_t;
import lcmloc.pose_t;

/**
 * What the pose view shows, accumulated from pose_t and gate_decision_t messages with no Swing:
 * the track (a bounded ring), the latest estimate and its position covariance, the gate's decisions
 * placed at the estimate of their time, and the NIS strip with its chi-square band. Thread-safe:
 * LCM's thread adds, Swing's thread reads snapshots.
 */
public final class PoseModel {
    /** One estimate on the track. */
    public static final class Point {
        public final long utime;
        public final double x;
        public final double y;
        public final double theta;

        Point(long utime, double x, double y, double theta) {
            this.utime = utime;
            this.x = x;
            this.y = y;
            this.theta = theta;
        }
    }

    /** One gate decision: where the vehicle was estimated, the map element, accepted or not. */
    public static final class Mark {
        public final long utime;
        public final double x;
        public final double y;
        public final int markerId;
        public final boolean accepted;
        public final String sensor;

        Mark(long utime, double x, double y, int markerId, boolean accepted, String sensor) {
            this.utime = utime;
            this.x = x;
            this.y = y;
            this.markerId = markerId;
            this.accepted = accepted;
            this.sensor = sensor;
        }
    }

    /** One NIS value and its 95 % band (NaN when the table has no band for its dimension). */
    public static final class Nis {
        public final long utime;
        public final double value;
        public final int dof;
        public final double low;
        public final double high;
        public final boolean accepted;

        Nis(long utime, double value, int dof, boolean accepted) {
            this.utime = utime;
            this.value = value;
            this.dof = dof;
            this.low = Chi2Band.has(dof) ? Chi2Band.low(dof) : Double.NaN;
            this.high = Chi2Band.has(dof) ? Chi2Band.high(dof) : Double.NaN;
            this.accepted = accepted;
        }

        /** True when the value lies in its band; false also when there is no band. */
        public boolean inBand() { return value >= low && value <= high; }
    }

    /** A consistent copy of the model for painting. */
    public static final class Snapshot {
        public final String filter;
        public final int status;
        public final List<Point> track;
        public final double[] covariance; // sxx, sxy, syy of the latest estimate, null before one
        public final List<Mark> marks;
        public final List<Nis> nis;
        public final long poses;
        public final long decisions;

        Snapshot(PoseModel m) {
            filter = m.filter;
            status = m.status;
            track = Collections.unmodifiableList(m.track.toList());
            covariance = m.covariance == null ? null : m.covariance.clone();
            marks = Collections.unmodifiableList(m.marks.toList());
            nis = Collections.unmodifiableList(m.nis.toList());
            poses = m.track.added();
            decisions = m.marks.added();
        }

        public Point last() { return track.isEmpty() ? null : track.get(track.size() - 1); }

        /** Fraction of the strip's NIS values inside their band (NaN with no value). */
        public double inBandFraction() {
            if (nis.isEmpty()) {
                return Double.NaN;
            }
            int in = 0;
            for (Nis n : nis) {
                in += n.inBand() ? 1 : 0;
            }
            return (double) in / nis.size();
        }
    }

    private final String gateChannel;
    private final Ring<Point> track;
    private final Ring<Mark> marks;
    private final Ring<Nis> nis;
    private String filter = "";
    private int status = pose_t.STATUS_UNINITIALIZED;
    private double[] covariance;

    /** A model keeping at most trackLength estimates, marks decisions and nisLength NIS values. */
    public PoseModel(String gateChannel, int trackLength, int marks, int nisLength) {
        this.gateChannel = gateChannel;
        this.track = new Ring<>(trackLength);
        this.marks = new Ring<>(marks);
        this.nis = new Ring<>(nisLength);
    }

    /** Decodes one message of channel (gate_decision_t on the gate channel, else pose_t). */
    public void accept(String channel, DataInput in) throws IOException {
        if (channel.equals(gateChannel)) {
            add(new gate_decision_t(in));
        } else {
            add(new pose_t(in));
        }
    }

    /** Adds an estimate; one with fewer than 2 states (or a short covariance) is ignored. */
    public synchronized void add(pose_t p) {
        if (p.dim < 2 || p.state.length < 2 || p.covariance.length < 2 || p.covariance[0].length < 2) {
            return;
        }
        double theta = p.dim >= 3 ? p.state[2] : 0.0;
        track.add(new Point(p.utime, p.state[0], p.state[1], theta));
        covariance = new double[] {p.covariance[0][0], p.covariance[0][1], p.covariance[1][1]};
        filter = p.filter == null ? "" : p.filter;
        status = p.status;
    }

    /**
     * Adds a gate decision of the track's filter (all decisions before the first estimate names
     * it); other filters' decisions (shadow filters on the same GATE channel) are ignored. The
     * decision is placed at the latest estimate, or dropped from the map view before there is one.
     */
    public synchronized void add(gate_decision_t g) {
        if (!filter.isEmpty() && g.filter != null && !g.filter.equals(filter)) {
            return;
        }
        nis.add(new Nis(g.utime, g.mahalanobis, g.dim, g.accepted));
        Point at = track.last();
        if (at != null) {
            marks.add(new Mark(g.utime, at.x, at.y, g.marker_id, g.accepted, g.sensor));
        }
    }

    public synchronized Snapshot snapshot() { return new Snapshot(this); }
}
